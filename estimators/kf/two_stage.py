"""Two-stage physics-constrained Kalman filter (Siegloff & Choi §III, method A).

State :math:`x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]`, random walk (eq. 12, 19);
first update with the suspension pseudo-measurement :math:`z = x + v_s`
(eq. 13, 20-22); second update with the rigid-body equilibrium as a soft
constraint :math:`b = A x + w_c` (eq. 17, 23-25). Joseph form throughout.

Tuning is per second (white-noise densities): :math:`Q = q\\,dt\\,I`,
:math:`R_s = r_s/\\Delta t_{nom}\\,I`, :math:`R_c = \\mathrm{diag}(r_c)/\\Delta t_{nom}` with the
log's nominal (median) interval, so that a gap grows the covariance and never
shrinks the measurement noise. Optional input-dependent densities (vehicle file
``[filter]``, default 0) add terms in the damper velocity, the hub acceleration and the
body accelerations (:mod:`wheelload.models.measurement_noise`, one Function, used here
and by the MHE, method E+C and the numpy joint filter). Guards (plausibility, innovation gate, fault
monitor, covariance limits) act inside the step: :mod:`wheelload.estimators.kf.guard`.

The per-sample step is one CasADi Function built from the model Functions in
``wheelload.models``; :meth:`TwoStageKF.run` maps it over a log in compiled
code (a generated C loop, the equivalent of ``mapaccum``; see ``compiled``).

Example
-------
>>> kf = TwoStageKF(load_vehicle("sports_car.toml"))
>>> estimates = kf.run(read_log("drive.csv")).to_pandas()
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.kalman import (
    predict,
    sequential_update,
    sequential_update_innovations,
    upper,
)
from wheelload.estimators.kf import guard
from wheelload.estimators.kf.guard import GuardSettings
from wheelload.estimators.logs.signals import Signals, rate_derivatives
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.protocol import Sample, sample_intervals
from wheelload.estimators.result import Estimate, SensorFault, StepFlag
from wheelload.models import (
    GATES,
    INPUTS,
    OPTIONAL_INPUTS,
    ModelParameters,
    Vehicle,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.input_validity import dependency_mask, sanitise
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
    input_index,
)
from wheelload.models.measurement_noise import DENSITIES as NOISE_DENSITY_ORDER
from wheelload.models.measurement_noise import INPUT_DENSITIES, measurement_noise_function
from wheelload.models.roll_split import SPLIT_NOISE_RATIO, roll_split_function

if TYPE_CHECKING:
    import pandas as pd

#: Order of the tuning vector.
TUNING = (
    "process_noise_density",
    "suspension_noise_density",
    "constraint_noise_vertical",
    "constraint_noise_pitch",
    "constraint_noise_roll",
    "sample_interval",
    *GuardSettings.names(),
    *INPUT_DENSITIES,
)
#: The filter's constant noise densities: the first entries of the tuning vector (vehicle
#: file [filter]); the input-dependent ones (default 0) are :data:`INPUT_DENSITIES`, last.
NOISE_DENSITIES = TUNING[:5]
#: Every density ``wheelload tune`` fits: the constant ones, then the input-dependent ones.
TUNED_DENSITIES = NOISE_DENSITIES + INPUT_DENSITIES
#: Position of each entry of the tuning vector.
TUNING_INDEX = {name: k for k, name in enumerate(TUNING)}
STEP_NAME = "wheelload_kf_step"
#: Nominal sample interval [s] where no log gives one (100 Hz).
DEFAULT_SAMPLE_INTERVAL = 0.01
_SAMPLE_INTERVAL = TUNING.index("sample_interval")
_GUARD_START = _SAMPLE_INTERVAL + 1
_GUARD_END = _GUARD_START + len(GuardSettings.names())
_NOISE_INDEX = [TUNING_INDEX[name] for name in NOISE_DENSITY_ORDER]
_RC_INDEX = [TUNING_INDEX[f"constraint_noise_{row}"] for row in ("vertical", "pitch", "roll")]
_VARIANCE_SCALE = TUNING.index("innovation_variance_scale")
_P_INDEX = {name: k for k, name in enumerate(ModelParameters.names())}


def tuning_vector(
    vehicle: Vehicle,
    sample_interval: float = DEFAULT_SAMPLE_INTERVAL,
    settings: GuardSettings | None = None,
) -> np.ndarray:
    r"""The filter tuning in :data:`TUNING` order: the vehicle file's, interval, guards.

    ``sample_interval`` is the log's nominal interval [s]: the measurement
    noise is :math:`R = r / \Delta t_{nominal}` whatever the gap before a
    sample. ``settings``: default the vehicle's
    (:func:`~wheelload.estimators.kf.guard.guard_settings_for`).
    """
    settings = guard.guard_settings_for(vehicle) if settings is None else settings
    tuning = vehicle.filter
    if not 0.0 < sample_interval < MAX_INTERVAL:
        raise ValueError(f"sample interval must be > 0 s and finite, got {sample_interval}")
    vector = np.array(
        [
            tuning.process_noise_density,
            tuning.suspension_noise_density,
            *tuning.constraint_noise_density,
            sample_interval,
            *settings.vector(),
            *tuning.input_densities(),
        ]
    )
    # The vehicle file's [filter] gate_scale (written by ``wheelload tune``) on the gate's S.
    vector[_VARIANCE_SCALE] *= tuning.gate_scale
    return vector


def noise_densities(vehicle: Vehicle) -> np.ndarray:
    """The vehicle file's noise densities in :data:`TUNED_DENSITIES` order (constant, then
    input-dependent)."""
    return tuning_vector(vehicle)[[TUNING_INDEX[name] for name in TUNED_DENSITIES]]


def nominal_interval(t: np.ndarray) -> float:
    """Median of the positive finite sample intervals of a log (default if none)."""
    dt = np.diff(np.asarray(t, float))
    dt = dt[np.isfinite(dt) & (dt > 0) & (dt < MAX_INTERVAL)]
    return float(np.median(dt)) if dt.size else DEFAULT_SAMPLE_INTERVAL


def _required(valid: ca.SX) -> ca.SX:
    """Validity of the inputs an update cannot do without (optional inputs count as valid)."""
    return ca.vertcat(
        *[1 if name in OPTIONAL_INPUTS else valid[i] for i, name in enumerate(INPUTS)]
    )


MAX_INTERVAL = 1e6  # s, longest sample interval taken as valid


def interval_is_valid(dt):
    """1 where the sample interval is finite and positive (NaN compares false)."""
    return ca.logic_and(dt > 0, dt < MAX_INTERVAL)


_TRAVEL_INDEX = input_index(TRAVEL)
_RATE_INDEX = input_index(TRAVEL_RATE)
_ACC_INDEX = input_index(SPECIFIC_FORCE)
_HUB_INDEX = input_index(HUB_ACCELERATION)
_BODY_RATE_INDEX = input_index(BODY_RATES + BODY_RATE_DERIVATIVES)


def _channel_drop(channel_ok: ca.SX) -> ca.SX:
    """Validity factor per input from the fault monitor's channels (d_fl..d_rr, ax, ay, az).

    A travel channel drops its travel and travel rate; an accelerometer axis drops
    that axis; every other input is kept.
    """
    factors = [1] * len(INPUTS)
    for i in range(4):
        factors[_TRAVEL_INDEX[i]] = channel_ok[i]
        factors[_RATE_INDEX[i]] = channel_ok[i]
    for j in range(3):
        factors[_ACC_INDEX[j]] = channel_ok[4 + j]
    return ca.vertcat(*factors)


def model_rows(suspension: ca.Function, equilibrium: ca.Function, u_raw, valid, p):
    """Pseudo-measurement, equilibrium and their masks from raw inputs and validity.

    Returns ``(z, A, b, mask_s, mask_c, dropped)``. An update needs the inputs
    of the paper's model (every term gated off: the Jacobian sparsity of the
    rows with zero gates); a term whose optional input is missing is gated off
    for the sample instead, and ``dropped`` (``wheelload.models.DROPPABLE``
    order) says which.
    """
    u = sanitise(u_raw, valid)
    z, A, b, dropped = model_equations(suspension, equilibrium, u, valid, p)
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    return z, A, b, mask_s, mask_c, dropped


def model_equations(suspension: ca.Function, equilibrium: ca.Function, u, valid, p):
    """``(z, A, b, dropped)`` from inputs ``u`` (0 where not ``valid``) with their terms gated."""
    gates, dropped = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    return z, A, b, dropped


def row_masks(suspension: ca.Function, equilibrium: ca.Function, u, u_raw, valid, p):
    """``(mask_s, mask_c)``: 1 for each row whose paper-model inputs are all valid."""
    paper = ca.DM.zeros(gates_function().size_out(0))
    mask_s = dependency_mask(suspension(u, paper, p), u_raw, _required(valid))
    mask_c = dependency_mask(equilibrium(u, paper, p)[1], u_raw, _required(valid))
    return mask_s, mask_c


def step_expressions(
    suspension: ca.Function,
    equilibrium: ca.Function,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
):
    """Symbolic inputs and outputs of one filter step built from the model Functions.

    ``measurement_noise(u, u_valid, densities, dt_nominal) -> (R_s, R_c)``
    defaults to :func:`~wheelload.models.measurement_noise.measurement_noise_function`.

    ``constraint_update(x, P, b, A, r_c, mask, gate) -> (x, P, y, S, use)``
    is the second stage; the default is the soft-constraint Kalman update
    (eq. 23-25), one row at a time. Outputs ``innovation`` and
    ``innovation_variance`` (7 each, update order: suspension FL, FR, RL, RR,
    then vertical, pitch, roll) are each row's pre-update innovation and its
    variance S; both are 0 for a row whose inputs are missing. The guards of
    :mod:`wheelload.estimators.kf.guard` (plausibility, innovation gate, fault
    monitor with state ``m``, covariance limits) act on the masks of the
    updates, so a guarded row changes neither x nor P.
    """
    x = ca.SX.sym("x", 4)
    P = ca.SX.sym("P", 4, 4)
    m = ca.SX.sym("m", guard.MONITOR_SIZE)
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid_raw = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", len(ModelParameters.names()))
    tuning = ca.SX.sym("tuning", len(TUNING))
    settings = guard.unpack(tuning[_GUARD_START:_GUARD_END])
    dt_nominal = tuning[_SAMPLE_INTERVAL]

    # A non-positive or non-finite interval skips the whole step: the state is held.
    dt_ok = interval_is_valid(dt)
    dt_safe = ca.if_else(dt_ok, dt, 1.0)
    dt_used = dt_safe * dt_ok

    # Missing or implausible inputs are replaced by zero and skip the updates they feed;
    # a body rate that jumps, or a derivative after a gated rate, counts as implausible.
    u_finite = sanitise(u_raw, valid_raw)
    in_range = guard.plausible_for(u_finite, p, settings)
    consistent, settle_next = guard.rate_consistency(
        u_finite, valid_raw, in_range, m, dt_used, settings
    )
    in_range = in_range * consistent
    valid_plausible = valid_raw * in_range
    u = sanitise(u_raw, valid_plausible)
    # The model terms take each missing or gated input's last valid value for
    # ``hold_time``, then drop; the rows needing the input are skipped. ``dropped`` (the
    # flags) marks a term without a live input, held or dropped.
    u_term, valid_term, held, hold_state = guard.hold_inputs(
        u, valid_plausible, m, dt_used, settings
    )
    z, A, b, _ = model_equations(suspension, equilibrium, u_term, valid_term, p)
    dropped = gates_function()(valid_plausible, p)[1]

    # Fault monitor: an isolated channel is dropped like a missing one. Its parity test
    # uses every model term the inputs allow (held inputs included), whatever the
    # [model] switches.
    parity = guard.parity_model(suspension, equilibrium, u_term, valid_term, p)
    # The fault monitor's parity test weighs the constant densities (the paper's R_c).
    rc_density = ca.vertcat(*[tuning[k] for k in _RC_INDEX])
    watch = guard.monitor(m, u, valid_plausible, *parity, dt_used, rc_density, settings)
    valid = valid_plausible * _channel_drop(watch.channel_ok)
    # The updates the channels left after the guards feed (an isolated channel's rows are
    # skipped; the model terms keep their inputs, as for the monitor).
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    mask_s = mask_s * dt_ok
    mask_c = mask_c * dt_ok

    # Measurement noise from the nominal interval: a gap grows P, never shrinks R.
    weight = p[_P_INDEX["mass"]] * guard.GRAVITY
    ceiling = weight * weight
    Q = ca.fmin(tuning[TUNING_INDEX["process_noise_density"]] * dt_used, ceiling) * ca.DM.eye(4)
    # R_s, R_c from the inputs (models/measurement_noise.py; constant with the default zeros).
    densities = ca.vertcat(*[tuning[k] for k in _NOISE_INDEX])
    noise = measurement_noise or measurement_noise_function()
    rs, rc = noise(u, valid_plausible, densities, dt_nominal)

    # R_s and R_c are diagonal: row-by-row updates equal the joint ones (eq. 20-25).
    reject, spread = m[guard.reject_slice()], m[guard.spread_slice()]
    x_pred, P_pred = predict(x, upper(P), Q)
    P_pred, limited_pred = guard.limit_covariance(P_pred, settings.covariance_floor, ceiling)
    H = ca.vertcat(ca.DM.eye(4), A)
    y_prior = ca.vertcat(z, b) - ca.mtimes(H, x_pred)
    S_prior = ca.vertcat(
        *[ca.mtimes(ca.mtimes(H[i, :], P_pred), H[i, :].T) for i in range(7)]
    ) + ca.vertcat(rs, rc)
    prior = guard.prior_failures(y_prior, S_prior, ca.vertcat(mask_s, mask_c), spread, settings)
    gate, record = guard.gate_rows(reject, spread, settings, prior)
    x_s, P_s, y_s, S_s, use_s = sequential_update_innovations(
        x_pred, P_pred, z, ca.DM.eye(4), rs, mask_s, gate
    )
    x_new, P_new, y_c, S_c, use_c = constraint_update(
        x_s, P_s, b, A, rc, mask_c, lambda i, y, S: gate(4 + i, y, S)
    )
    # No travel row at all (IMU-only): the weak roll-split row observes the warp, beside
    # the roll moment it splits, so only when that row was used (with no data at all the
    # step is a pure prediction).
    no_travel = (1 - mask_s[0]) * (1 - mask_s[1]) * (1 - mask_s[2]) * (1 - mask_s[3])
    mask_split = dt_ok * no_travel * use_c[2]
    r_split = SPLIT_NOISE_RATIO * rc[2:3]
    x_new, P_new = sequential_update(
        x_new, P_new, ca.DM.zeros(1), roll_split_function()(p), r_split, mask_split
    )
    P_new, limited_new = guard.floor_covariance(P_new, settings.covariance_floor)
    # An update that would take a load out of +-load_limit m g (or to a non-finite value)
    # is not taken: the sample is the prediction, so no hostile sample poisons the state.
    total = guard.total_range(m, b[0], mask_c[0], weight)
    bounded = guard.within_load_limit(x_new, x_pred, total, weight, settings)
    x_new = ca.if_else(bounded, x_new, x_pred)
    P_new = ca.if_else(bounded, P_new, P_pred)
    use_s, use_c = use_s * bounded, use_c * bounded

    std = ca.sqrt(ca.fmax(ca.diag(P_new), 0))
    residual = b - ca.mtimes(A, x_new)
    used = ca.vertcat(use_s, use_c, (1 - dropped) * dt_ok)
    available = ca.vertcat(mask_s, mask_c)
    innovation = ca.vertcat(y_s, y_c) * available
    innovation_variance = ca.vertcat(S_s, S_c) * available
    m_next = guard.with_gate_state(
        watch.m_next,
        guard.reject_times(reject, record, available, dt_used),
        guard.next_spread(spread, record, available, dt_used, settings),
    )
    m_next = guard.with_hold_state(m_next, hold_state, settle_next, total)
    status = _status(
        record, available, valid_raw, in_range, watch.fault,
        ca.logic_or(limited_pred, limited_new), watch.jump, held, 1 - bounded,
    )  # fmt: skip
    inputs = [x, P, m, u_raw, valid_raw, dt, p, tuning]
    outputs = [
        x_new, P_new, m_next, std, residual, used, z, innovation, innovation_variance,
        status, watch.statistic, watch.fault,
    ]  # fmt: skip
    return inputs, outputs


def _status(record, available, valid_raw, in_range, fault, limited, jump, held, unbounded):
    """Indicators of the guard flags (:data:`GUARD_FLAGS` order)."""

    def any_of(values):
        result = 0
        for value in values:
            result = ca.logic_or(result, value)
        return result

    gated = [available[i] * (1 - ca.logic_or(*record[i][:2])) for i in range(7)]
    released = [available[i] * (1 - record[i][0]) * record[i][1] for i in range(7)]
    implausible = [valid_raw[i] * (1 - in_range[i]) for i in range(len(INPUTS))]
    return ca.vertcat(
        any_of(gated),
        any_of(released),
        any_of([implausible[k] for k in _TRAVEL_INDEX + _RATE_INDEX]),
        any_of([implausible[k] for k in _ACC_INDEX + _HUB_INDEX]),
        implausible[INPUTS.index("vx")],
        any_of([fault[i] for i in range(4)]),
        any_of([fault[i] for i in range(4, 7)]),
        limited,
        any_of([jump[i] for i in range(4)]),
        any_of([implausible[k] for k in _BODY_RATE_INDEX]),
        any_of([held[k] for k in range(len(INPUTS))]),
        unbounded,
    )


STEP_INPUT_NAMES = ["x", "P", "m", "u", "u_valid", "dt", "p", "tuning"]
STEP_OUTPUT_NAMES = [
    "x_next", "P_next", "m_next", "std", "residual", "used", "z", "innovation",
    "innovation_variance", "status", "fault_statistic", "fault",
]  # fmt: skip
#: The step's carried state: x, P and the monitor m.
N_CARRIED = 3


def step_function(
    suspension: ca.Function | None = None,
    equilibrium: ca.Function | None = None,
    name: str = STEP_NAME,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
) -> ca.Function:
    """The filter step as a CasADi Function (model Functions default to ``wheelload.models``)."""
    inputs, outputs = step_expressions(
        suspension or suspension_function(),
        equilibrium or equilibrium_function(),
        constraint_update=constraint_update,
        measurement_noise=measurement_noise,
    )
    # The suspension and equilibrium share the body motion and attitude: one copy.
    outputs = ca.cse(outputs)
    return ca.Function(name, inputs, outputs, STEP_INPUT_NAMES, STEP_OUTPUT_NAMES)


def without_monitor(step: ca.Function) -> ca.Function:
    """``step`` for callers that carry only x and P: the monitor starts empty every call.

    ``(x, P, u, u_valid, dt, p, tuning) -> (x_next, P_next, std, residual,
    used, z, innovation, innovation_variance)``.
    """
    inputs = step.sx_in()
    named = dict(
        zip(
            STEP_OUTPUT_NAMES,
            step.call([*inputs[:2], ca.DM.zeros(step.sparsity_in(2)), *inputs[3:]]),
        )
    )
    kept = [
        name
        for name in STEP_OUTPUT_NAMES
        if name not in ("m_next", "status", "fault_statistic", "fault")
    ]
    names_in = [name for name in STEP_INPUT_NAMES if name != "m"]
    return ca.Function(
        f"{step.name()}_xp",
        [*inputs[:2], *inputs[3:]],
        [named[name] for name in kept],
        names_in,
        kept,
    )


#: The seven update rows in update order (innovation outputs).
UPDATE_ROWS = (
    "suspension_fl", "suspension_fr", "suspension_rl", "suspension_rr",
    "vertical", "pitch", "roll",
)  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class Innovations:
    """Pre-update innovations of the seven update rows of ``n`` samples (:data:`UPDATE_ROWS`).

    ``innovation`` :math:`y` [N, N, N m], ``variance`` :math:`S` [its unit^2],
    both 0 where the row's inputs are missing; ``used`` is True where the
    row updated the state.
    """

    t: np.ndarray  # (n,)
    innovation: np.ndarray  # (n, 7)
    variance: np.ndarray  # (n, 7)
    used: np.ndarray  # (n, 7) bool

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t, innovation_<row>.., variance_<row>.., used_<row>..``."""
        import pandas as pd

        columns = {"t": self.t}
        columns.update(
            {f"innovation_{r}": self.innovation[:, i] for i, r in enumerate(UPDATE_ROWS)}
        )
        columns.update({f"variance_{r}": self.variance[:, i] for i, r in enumerate(UPDATE_ROWS)})
        columns.update({f"used_{r}": self.used[:, i] for i, r in enumerate(UPDATE_ROWS)})
        return pd.DataFrame(columns)


@dataclass(frozen=True)
class FilterState:
    """Explicit filter state: loads ``x`` [N], covariance ``P`` [N^2], fault monitor ``m``."""

    x: np.ndarray
    P: np.ndarray
    m: np.ndarray = field(default_factory=lambda: np.zeros(guard.MONITOR_SIZE))


def input_matrix(signals: Signals) -> np.ndarray:
    """The per-sample inputs of a log in :data:`INPUTS` order, shape (len(INPUTS), n).

    Optional channels the log lacks are NaN (their terms are dropped).
    """
    n = len(signals)

    def optional(values: np.ndarray | None, width: int) -> np.ndarray:
        return np.full((width, n), np.nan) if values is None else values.T

    rows = np.vstack(
        [
            signals.d.T,
            signals.v.T,
            signals.acc.T,
            signals.vx[None, :],
            optional(signals.rates, 3),
            rate_derivatives(signals).T,
            optional(signals.hub, 4),
        ]
    )
    if rows.shape[0] != len(INPUTS):
        raise RuntimeError(f"input_matrix builds {rows.shape[0]} rows for {len(INPUTS)} INPUTS")
    return rows


def flags_from_used(used: np.ndarray) -> np.ndarray:
    """Per-sample :class:`StepFlag` bits from the ``used`` output (7 + 4 dropped terms x n).

    A ``used`` of only the seven update rows (a method without model terms)
    gives their bits only.
    """
    skipped = used < 0.5
    bits = np.array([flag.value for flag in StepFlag.update_flags()[: used.shape[0]]])
    return (skipped * bits[:, None]).sum(axis=0).astype(np.int64)


def flags_from_outputs(used: np.ndarray, status: np.ndarray) -> np.ndarray:
    """Per-sample flags from the ``used`` (7 x n) and ``status`` (8 x n) outputs."""
    bits = np.array([flag.value for flag in StepFlag.guard_flags()])
    guarded = ((status > 0.5) * bits[:, None]).sum(axis=0).astype(np.int64)
    return flags_from_used(used) | guarded


_NO_TIME = np.array([np.nan])  # the time of a single step's estimate (shared, read-only)
_NO_TIME.flags.writeable = False


class TwoStageKF:
    """Two-stage physics-constrained Kalman filter for the four wheel loads.

    Parameters
    ----------
    vehicle
        Vehicle parameters and filter tuning.
    static
        Static wheel loads [N] used as pseudo-measurement offsets and initial
        estimate; default: the vehicle file's static load distribution.
    step
        The step Function, e.g. ``step_function(suspension=...)`` with another
        model; default :func:`step_function`.
    """

    name = "two-stage KF"

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        static: np.ndarray | None = None,
        step: ca.Function | None = None,
        guard_settings: GuardSettings | None = None,
        sample_interval: float | None = None,
    ) -> None:
        self.vehicle = vehicle
        self.parameters = ModelParameters.from_vehicle(vehicle, static)
        self.p = self.parameters.vector()
        if guard_settings is None:
            guard_settings = guard.guard_settings_for(vehicle)
        self.guard_settings = guard_settings
        self.sample_interval = sample_interval
        self.tuning = tuning_vector(
            vehicle, sample_interval or DEFAULT_SAMPLE_INTERVAL, guard_settings
        )
        if step is None:
            from wheelload.estimators.kf.step_cache import default_step_function

            step = default_step_function()  # step_function(), loaded from disk when built before
        self.step_function = step

    def tuning_for(self, sample_interval: float) -> np.ndarray:
        """:attr:`tuning` with the nominal interval ``sample_interval`` [s]."""
        if not 0.0 < sample_interval < MAX_INTERVAL:
            raise ValueError(f"sample interval must be > 0 s and finite, got {sample_interval}")
        tuning = np.array(self.tuning, float)
        tuning[_SAMPLE_INTERVAL] = sample_interval
        return tuning

    def initial_state(self) -> FilterState:
        """Static loads with covariance ``initial_std^2 I`` (at most ``(m g)^2``)."""
        x0 = np.array(self.parameters.static(), dtype=float)
        weight = self.parameters.mass * guard.GRAVITY
        variance = min(self.vehicle.filter.initial_std, weight) ** 2
        return FilterState(x0, variance * np.eye(4))

    def step(self, state: FilterState, sample: Sample, dt: float) -> tuple[FilterState, Estimate]:
        """One prediction and both updates; returns the new state and the estimate.

        The measurement noise uses the ``sample_interval`` given to the
        constructor; without one, ``dt`` itself (a gap then shrinks it).
        Runs the step Function in compiled C on preallocated buffers
        (:mod:`wheelload.estimators.loops.fast_step`); the same numbers as
        :meth:`reference_step`.
        """
        fast = self._fast_step
        if self.sample_interval is None:  # else set once in _fast_step
            nominal = dt if 0.0 < dt < MAX_INTERVAL else self.tuning[_SAMPLE_INTERVAL]
            fast.set_interval(_SAMPLE_INTERVAL, nominal)
        x, P, m, std, residual, flags = fast.call_sample(state.x, state.P, state.m, sample, dt)
        estimate = Estimate(
            t=_NO_TIME,
            loads=x.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=np.array([flags], dtype=np.int64),
        )
        return FilterState(x, P, m), estimate

    def live(self, state: FilterState | None = None):
        """A :class:`~wheelload.estimators.loops.fast_step.LiveFilter` from ``state`` (default:
        initial).

        The lean per-sample path: the state stays in the compiled step's
        buffer and each update returns views, not new objects; the same
        numbers as :meth:`step` and :meth:`reference_step`.
        """
        from wheelload.estimators.loops.fast_step import LiveFilter

        state = state or self.initial_state()
        return LiveFilter(
            self._fast_step,
            state.x,
            state.P,
            state.m,
            interval_index=None if self.sample_interval is not None else _SAMPLE_INTERVAL,
            default_interval=float(self.tuning[_SAMPLE_INTERVAL]),
            max_interval=MAX_INTERVAL,
        )

    @functools.cached_property
    def _step(self) -> ca.Function:
        """:attr:`step_function` without the fault monitor (built on first use)."""
        return without_monitor(self.step_function)

    @functools.cached_property
    def _fast_step(self):
        """The step compiled once (cached by source hash), with this filter's p and tuning."""
        from wheelload.estimators.loops.fast_step import CompiledStep

        fast = CompiledStep(self.step_function, MAX_INTERVAL)
        fast.set_fixed(self.p, self.tuning)
        return fast

    def reference_step(
        self, state: FilterState, sample: Sample, dt: float
    ) -> tuple[FilterState, Estimate]:
        """:meth:`step` through CasADi's virtual machine and numpy: the reference for tests."""
        u = sample.vector()
        valid = np.isfinite(u).astype(float)
        nominal = self.sample_interval or (dt if 0.0 < dt < MAX_INTERVAL else None)
        tuning = self.tuning if nominal is None else self.tuning_for(nominal)
        flat = np.concatenate(
            [
                state.x,
                np.ravel(state.P, order="F"),
                state.m,
                np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0),
                valid,
                [dt],
                self.p,
                tuning,
            ]
        )
        out = np.split(np.asarray(self._flat_step(flat)).ravel(), self._flat_splits)
        x, P, m, std, residual, used = out[:6]
        status = out[STEP_OUTPUT_NAMES.index("status")]
        flags = flags_from_outputs(used.reshape(-1, 1), status.reshape(-1, 1))
        if not 0.0 < dt < MAX_INTERVAL:
            flags |= StepFlag.STEP_REJECTED
        estimate = Estimate(
            t=np.array([np.nan]),
            loads=x.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=flags,
        )
        return FilterState(x, P.reshape(4, 4, order="F"), m), estimate

    @functools.cached_property
    def _flat_step(self) -> ca.Function:
        """The step with inputs and outputs stacked into one vector each (one cheap call)."""
        inputs = self.step_function.sx_in()
        outputs = self.step_function.call(inputs)
        return ca.Function(
            f"{self.step_function.name()}_flat",
            [ca.vertcat(*[ca.vec(i) for i in inputs])],
            [ca.vertcat(*[ca.vec(o) for o in outputs])],
        )

    @functools.cached_property
    def _flat_splits(self) -> np.ndarray:
        step = self.step_function
        return np.cumsum([step.nnz_out(i) for i in range(step.n_out())])[:-1]

    def run(self, signals: Signals, state: FilterState | None = None) -> Estimate:
        """Filter a whole log in compiled code; same numbers as repeated :meth:`step`.

        The nominal interval is the constructor's ``sample_interval`` or the
        log's median interval.
        """
        return self._run(signals, state, with_covariance=False)[0]

    def run_with_covariance(
        self, signals: Signals, state: FilterState | None = None
    ) -> tuple[Estimate, np.ndarray]:
        """As :meth:`run`, also returning the posterior covariances, shape (n, 4, 4)."""
        return self._run(signals, state, with_covariance=True)[:2]

    def smooth(self, signals: Signals, state: FilterState | None = None) -> Estimate:
        """Rauch–Tung–Striebel smoothed loads of a whole log (``estimators/kf/smoother.py``)."""
        from wheelload.estimators.kf.smoother import rts_smooth

        filtered, covariances = self.run_with_covariance(signals, state)
        A, _ = equilibrium_function()(np.zeros(len(INPUTS)), np.zeros(len(GATES)), self.p)
        dt = sample_intervals(signals.t)
        return rts_smooth(filtered, covariances, dt, self._step, self.p, self.tuning, A)

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        """This filter's step looped over a log in C (state x, P, m carried)."""
        return CompiledLoop(self.step_function, N_CARRIED, ("u", "u_valid", "dt"))

    def _run(self, signals: Signals, state: FilterState | None, with_covariance: bool):
        state = state or self.initial_state()
        u = input_matrix(signals).T
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = sample_intervals(signals.t)[:, None]
        tuning = self.tuning_for(self.sample_interval or nominal_interval(signals.t))
        _, history, outputs = self._loop(
            [state.x, state.P, state.m],
            [self.p, tuning],
            [u, valid, dt],
            record=(0, 1) if with_covariance else (0,),
        )
        named = dict(zip(STEP_OUTPUT_NAMES[N_CARRIED:], outputs, strict=True))
        used = named["used"]
        estimate = Estimate(
            t=signals.t.copy(),
            loads=history[0],
            std=named["std"],
            residual=named["residual"],
            flags=flags_from_outputs(used.T, named["status"].T) | signals.input_flags(),
            sensor_faults=sensor_faults(signals.t, named["fault"], named["fault_statistic"]),
        )
        covariances = history[1].reshape(-1, 4, 4) if with_covariance else None
        innovations = Innovations(
            t=signals.t.copy(),
            innovation=named["innovation"],
            variance=named["innovation_variance"],
            used=used[:, :7] > 0.5,
        )
        return estimate, covariances, innovations

    def run_innovations(
        self, signals: Signals, state: FilterState | None = None
    ) -> tuple[Estimate, Innovations]:
        r"""As :meth:`run`, also returning every update row's innovation and its variance.

        The innovations of the sequential filter are independent standard
        normals under the model once divided by :math:`\sqrt{S}`, so the log
        likelihood of the tuning is :math:`-\tfrac12 \sum (\log 2\pi S + y^2 / S)`
        over the rows used (Mehra 1970).
        """
        estimate, _, innovations = self._run(signals, state, with_covariance=False)
        return estimate, innovations


def sensor_faults(
    t: np.ndarray, fault: np.ndarray, statistic: np.ndarray
) -> tuple[SensorFault, ...]:
    """One record per isolated fault: ``channel, start, end`` [s] and the peak ``statistic``.

    ``fault`` and ``statistic`` are the step outputs, shape (n, 7), channels
    :data:`~wheelload.estimators.kf.guard.FAULT_CHANNELS`; ``end`` is the time of
    the last flagged sample.
    """
    rows = []
    for j, channel in enumerate(guard.FAULT_CHANNELS):
        on = np.concatenate([[False], fault[:, j] > 0.5, [False]])
        starts = np.flatnonzero(on[1:] & ~on[:-1])
        ends = np.flatnonzero(~on[1:] & on[:-1])
        for start, end in zip(starts, ends, strict=True):
            rows.append(
                SensorFault(
                    channel=channel,
                    start=float(t[start]),
                    end=float(t[end - 1]),
                    statistic=float(np.max(statistic[start:end, j])),
                )
            )
    return tuple(sorted(rows, key=lambda fault: fault.start))
