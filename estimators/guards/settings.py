r"""Settings of the filter step's guards: plausibility, innovation gate, limits, fault monitor.

One :class:`GuardSettings` entry per threshold, each an entry of the tuning vector
(:data:`~wheelload.estimators.kf.tuning.TUNING`), so the generated C takes them at run
time. The guards build CasADi expressions inside the symbolic filter step
(:func:`wheelload.estimators.kf.step.step_expressions`), so the Python step, the compiled
loop and the generated C share one implementation:

- :mod:`wheelload.estimators.guards.plausibility`: input ranges, rate consistency, held inputs;
- :mod:`.innovation_gate`: the :math:`\chi^2_1` gate per update row, with release;
- :mod:`.limits`: the state limit and the covariance floor and ceiling;
- :mod:`.fault_monitor`: stuck channels and parity-space fault isolation (Gertler 1998, ch. 5);
- :mod:`.monitor_state`: the layout of the state ``m`` they carry.

Example
-------
>>> settings = guard_settings_for(load_vehicle("sports_car.toml"))
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import SimpleNamespace

import casadi as ca

from wheelload.models import Vehicle

#: Channels the fault monitor can isolate, in its output order.
FAULT_CHANNELS = ("d_fl", "d_fr", "d_rl", "d_rr", "ax", "ay", "az")


@dataclass(frozen=True, kw_only=True)
class GuardSettings:
    """Thresholds of the guards (all > 0); defaults tested on the bundled scenarios."""

    innovation_gate: float = 9.0  # chi^2_1 threshold on y^2 / S (3 sigma)
    gate_release_time: float = 0.005  # s failing the gate after which a row is taken
    spread_time_constant: float = 1.0  # s, memory of each row's innovation spread
    max_acceleration: float = 3.0  # g, |ax|, |ay|, |az|
    max_speed: float = 120.0  # m/s, |vx|
    max_travel_rate: float = 5.0  # m/s, |v|
    travel_range: float = 1.0  # |d| <= travel_range * m g / k: spring force of the whole weight
    covariance_floor: float = 1.0  # N, smallest standard deviation kept
    stuck_time: float = 0.25  # s without change while another corner moves
    stuck_motion: float = 1.5e-4  # m another corner must move within stuck_time (4 LSB, 12 bit)
    stuck_time_still: float = 0.5  # s without change while another corner only flickers
    parity_time_constant: float = 1.0  # s, low-pass of the parity residual
    travel_fault: float = 0.005  # m, smallest travel-sensor fault isolated
    ax_fault: float = 1.2  # m/s^2, smallest ax fault isolated
    ay_fault: float = 0.3  # m/s^2, smallest ay fault isolated
    az_fault: float = 1.2  # m/s^2, smallest az fault isolated
    isolation_fraction: float = 0.9  # share of residual energy one channel must explain
    # An accelerometer axis' fault estimate is split into a bias and a part that grows with
    # the axis' acceleration (a gain the file has wrong: springs, bars, mass, CG height) over
    # gain_time_constant; below gain_acceleration a steady estimate is a bias, above it a
    # gain (fault_monitor.gain_bias_split); gain_ridge weighs that preference. The axis is
    # isolated only when the bias is at least bias_share of the estimate.
    gain_time_constant: float = 1.0  # s
    gain_acceleration: float = 1.0  # m/s^2
    gain_ridge: float = 0.05
    bias_share: float = 0.33  # least share of an axis' fault estimate that is a bias
    fault_confirm_time: float = 0.2  # s a parity fault must persist
    fault_clear_time: float = 1.0  # s clean before an isolated channel is taken back
    # S in the gate and the spread's clip times this: ``wheelload tune`` scales the noise
    # densities by c and the file's [filter] gate_scale = 1/c lands here, so the gate and
    # the spread see the S they had and make the same decisions.
    innovation_variance_scale: float = 1.0
    # The model's own parity spread: a fault is isolated only beyond max(limit, factor * the
    # fault the clean residual of the last parity_spread_time would look like).
    parity_spread_time: float = 30.0  # s, memory of the parity residual's mean square
    parity_spread_factor: float = 2.0  # times the residual's spread, in fault units
    stuck_corners: float = 2.0  # other corners that must move for a still one to be stuck
    # Body rates and their derivatives. On the plant's scenarios (both bundled vehicles,
    # roughness D included, 100 Hz) |w| <= 0.87 rad/s, |dw|/dt <= 17 rad/s^2 between
    # samples and the 20 Hz differentiator's |w_dot| <= 16.6 rad/s^2: the limits leave a
    # factor of about 4 and 2.4 (``wheelload bench hostile --ranges`` measures them).
    max_body_rate: float = 4.0  # rad/s, |wx|, |wy|, |wz|
    max_angular_acceleration: float = 40.0  # rad/s^2, |w_dot| and |dw| / elapsed time
    rate_settle_time: float = 0.1  # s a derivative is not taken after its rate was gated
    hold_time: float = 0.15  # s a term holds a missing or gated input's last valid value
    load_limit: float = 3.0  # m g, largest |Fz| an update may reach
    total_margin: float = 0.25  # m g the total load may pass the log's own vertical-row range
    # The step's interval against the nominal one (tuning ``sample_interval``, which sets the
    # measurement noise): a dt below sample_interval / interval_band is refused (the log is
    # faster than the nominal interval: the noise would be wrong; INTERVAL_SHORT), one above
    # sample_interval * interval_band is taken and flagged (a gap, or a slower log;
    # INTERVAL_LONG).
    interval_band: float = 1.5  # > 1

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool)
            if not (number and 0.0 < value < float("inf")):
                raise ValueError(f"guard setting {field.name} must be > 0 and finite, got {value}")
        if self.isolation_fraction >= 1.0:
            raise ValueError("guard setting isolation_fraction must be below 1")
        if self.interval_band <= 1.0:
            raise ValueError("guard setting interval_band must be above 1")

    @staticmethod
    def names() -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(GuardSettings))

    def vector(self) -> list[float]:
        return [float(getattr(self, name)) for name in self.names()]


#: The default thresholds.
DEFAULT_GUARD = GuardSettings()

#: Guards out of reach: the filter as it was before the guards.
GUARDS_OFF = GuardSettings(
    **dict.fromkeys(
        (
            "innovation_gate",
            "gate_release_time",
            "max_acceleration",
            "max_speed",
            "max_travel_rate",
            "travel_range",
            "stuck_time",
            "stuck_time_still",
            "travel_fault",
            "ax_fault",
            "ay_fault",
            "az_fault",
            "max_body_rate",
            "max_angular_acceleration",
            "load_limit",
            "total_margin",
        ),
        1e300,
    ),
    spread_time_constant=1.0,
    covariance_floor=1e-12,
    rate_settle_time=1e-300,
    hold_time=1e-300,
)


def guard_settings_for(vehicle: Vehicle, base: GuardSettings = DEFAULT_GUARD) -> GuardSettings:
    """``base`` with the fault limits of the vehicle file's ``[filter.faults]``.

    A model that explains less of a vehicle's motion (a larger parity residual on
    clean logs) needs larger limits, or clean driving is isolated as a fault.
    """
    limits = vehicle.filter.faults
    return dataclasses.replace(
        base,
        travel_fault=limits.travel_fault,
        ax_fault=limits.ax_fault,
        ay_fault=limits.ay_fault,
        az_fault=limits.az_fault,
        gain_acceleration=limits.gain_acceleration,
    )


def unpack(vector: ca.SX) -> SimpleNamespace:
    """The settings as symbols, by name, from the guard part of the tuning vector."""
    return SimpleNamespace(**{name: vector[k] for k, name in enumerate(GuardSettings.names())})
