"""Layout of the filter step's carried guard state ``m`` (fault monitor, gate, held inputs).

One vector carried from sample to sample by the step (input ``m``, output ``m_next``), declared
once in :data:`MONITOR`: the fault monitor's slots (:mod:`.fault_monitor`), the innovation
gate's rejection times and spreads (:mod:`.innovation_gate`), then each input's held value and
hold time, the rate derivatives' settle times (:mod:`wheelload.estimators.guards.plausibility`), the
range of the vertical row (:mod:`.limits`), the reported sigma's running means
(:mod:`.reported_std`) and the payload filter (:mod:`wheelload.estimators.kf.payload`). It starts
at zero. Every slice below is derived from the declaration.

Example
-------
>>> m = np.zeros(MONITOR.size)
>>> MONITOR.value(m, "payload")
array([0., 0., 0., 0.])
"""

from __future__ import annotations

from wheelload.estimators.kernels.layout import Field, Layout
from wheelload.models.inputs import BODY_RATES, INPUTS

_CHANNELS = 7  # the fault channels: four travels, three accelerometer axes (guard.FAULT_CHANNELS)
_ROWS = 7  # the update rows: four suspension, three equilibrium

#: The carried state ``m``, in order.
MONITOR = Layout(
    "monitor_state",
    (
        Field("d_prev", 4, "m", doc="each travel's previous valid value"),
        Field("frozen", 4, "s", doc="how long each travel has not moved while the car did"),
        Field("rbar", 3, "N, N m", doc="low-passed equilibrium residual (parity)"),
        Field("persist", _CHANNELS, "s", doc="how long each channel's fault test has fired"),
        Field("clear", _CHANNELS, "s", doc="how long each channel's test has been clear"),
        Field("fault", _CHANNELS, "", doc="1 while a channel is isolated"),
        Field("reject", _ROWS, "s", doc="each row's time failing the innovation gate"),
        Field("spread", _ROWS, "", doc="each row's innovation spread (gate)"),
        Field("anchor", 4, "m", doc="each travel's value when the stuck test last moved"),
        Field("moved", 4, "", doc="1 once a travel moved since its anchor"),
        Field("jump", 4, "", doc="1 while a travel that jumped is frozen"),
        Field("parity_mean", 3, "N, N m", doc="running mean of the parity residual"),
        Field("parity_variance", 3, "N^2, N^2 m^2", doc="running variance of the residual"),
        Field("parity_weight", 1, "", doc="weight of the running means"),
        # The low-passed covariance the unknown payload leaves in the residual (upper
        # triangle: 00, 01, 02, 11, 12, 22), beside the low-passed residual it may explain.
        Field("unexplained", 6, "N^2, N^2 m, N^2 m^2", doc="payload's residual covariance"),
        # Each accelerometer axis' excitation (ax, ay, az - g), low-passed like the residual,
        # and per axis the weighted means of the bias/gain split (fault_monitor.gain_bias_split).
        Field("excitation", 3, "m/s^2", doc="low-passed accelerometer excitation"),
        Field("gain_sums", 15, "", doc="per axis the bias/gain split's weighted means"),
        # Each input's last valid value, its remaining hold time, and each rate derivative's
        # remaining settle time after a gated rate.
        Field("held", len(INPUTS), "input units", doc="each input's last valid value"),
        Field("credit", len(INPUTS), "s", doc="each input's remaining hold time"),
        Field("settle", len(BODY_RATES), "s", doc="each rate derivative's settle time"),
        Field("total", 2, "N", doc="lowest and highest vertical-row b so far, less the weight"),
        # The reported sigma's running means (:mod:`.reported_std`): per wheel the squared
        # equilibrium residual at the pseudo-measurement, then the squared suspension innovation.
        Field("sigma_residual", 4, "N^2", doc="running mean square of the residual"),
        Field("sigma_innovation", 4, "N^2", doc="running mean square of the innovation"),
        # The payload filter (:mod:`.payload`): its state and covariance (column-major); whether
        # the step has taken a sample (0: the payload prior is taken on the next one); whether
        # each travel channel has had a valid sample (0: no previous value to jump from).
        Field("payload", 4, "kg, m", doc="payload mass and position"),
        Field("payload_covariance", 16, "kg^2, kg m, m^2", doc="its covariance, column-major"),
        Field("started", 1, "", doc="1 once the step has taken a sample"),
        Field("travel_seen", 4, "", doc="1 once a travel channel has had a valid sample"),
    ),
)
#: The fault monitor's own fields (:func:`.fault_monitor.monitor` returns them by name).
WATCH = MONITOR.subset(
    "fault_monitor",
    [
        name
        for name in MONITOR.field_names()[: MONITOR.field_names().index("held")]
        if name not in ("reject", "spread")
    ],
)
#: The held inputs' fields (:func:`.plausibility.hold_inputs`' state, in this order).
HOLD = MONITOR.subset("hold_state", ("held", "credit"))
#: The reported sigma's running means (:func:`.reported_std.sigma_features`, in this order).
SIGMA_MEANS = MONITOR.subset("sigma_means", ("sigma_residual", "sigma_innovation"))

D_PREV, FROZEN, RBAR = MONITOR.slice("d_prev"), MONITOR.slice("frozen"), MONITOR.slice("rbar")
PERSIST, CLEAR, FAULT = MONITOR.slice("persist"), MONITOR.slice("clear"), MONITOR.slice("fault")
REJECT, SPREAD = MONITOR.slice("reject"), MONITOR.slice("spread")
ANCHOR, MOVED, JUMP = MONITOR.slice("anchor"), MONITOR.slice("moved"), MONITOR.slice("jump")
PARITY_MEAN = MONITOR.slice("parity_mean")
PARITY_VARIANCE = MONITOR.slice("parity_variance")
PARITY_WEIGHT = MONITOR.slice("parity_weight")
UNEXPLAINED, EXCITATION = MONITOR.slice("unexplained"), MONITOR.slice("excitation")
GAIN_SUMS = MONITOR.slice("gain_sums")
HELD, CREDIT, SETTLE = MONITOR.slice("held"), MONITOR.slice("credit"), MONITOR.slice("settle")
TOTAL = MONITOR.slice("total")
SIGMA_RESIDUAL = MONITOR.slice("sigma_residual")
SIGMA_INNOVATION = MONITOR.slice("sigma_innovation")
SIGMA_SLOTS = MONITOR.span("sigma_residual", "sigma_innovation")
PAYLOAD = MONITOR.slice("payload")
PAYLOAD_COVARIANCE = MONITOR.slice("payload_covariance")
STARTED = MONITOR.index("started")
TRAVEL_SEEN = MONITOR.slice("travel_seen")
MONITOR_SIZE = MONITOR.size
