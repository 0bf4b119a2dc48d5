"""Scenario settings (:mod:`wheelload.studies.drive.scenarios`), recorded in the log metadata."""

from __future__ import annotations

from dataclasses import dataclass, field

from wheelload.models.plant.slip_control import SlipControl

#: ABS and traction control as production threshold systems tune them: the torque is
#: released only once the wheel's slip is past the force peak (1.5 times the peak slip, on
#: the unstable side, where the wheel runs away: a threshold system's wheel-deceleration
#: trigger) and rebuilt while it is below the peak, so each build probes past the peak
#: again and the modulator cycles (4-10 Hz) for as long as the driver demands more than
#: the grip. The plant's default (:class:`~wheelload.models.plant.slip_control.SlipControl`)
#: holds between 0.6 and 0.9 of the peak slip instead and settles at the limit.
THRESHOLD_SLIP_CONTROL = SlipControl(slip_release=1.5, slip_apply=1.0)


@dataclass(frozen=True, kw_only=True)
class BeyondGrip:
    """The turns' speed change demanded beyond a low-friction road's grip.

    The turn is driven slower (``speed_scale``, so that it holds on the road), the speed
    change is asked at ``speed_rate`` (a firm stop or full throttle on a dry road), the
    driver's grip limit assumes the dry road's ``driver_friction`` (so the demand is not
    scaled to the road) and the plant's ABS/TCS is ``slip_control``
    (:data:`THRESHOLD_SLIP_CONTROL`: the wheels cycle past the force peak).
    """

    speed_scale: float = 0.6  # -, the turn's speeds times this
    speed_rate: float = 8.0  # m/s^2, the braking / accelerating rate asked for
    driver_friction: float = 1.15  # -, the friction the driver's grip limit assumes
    slip_control: SlipControl = THRESHOLD_SLIP_CONTROL

    def __post_init__(self) -> None:
        for key in ("speed_scale", "speed_rate", "driver_friction"):
            if not getattr(self, key) > 0.0:
                raise ValueError(f"beyond-grip '{key}' must be > 0, got {getattr(self, key)}")


@dataclass(frozen=True, kw_only=True)
class Options:
    """Scenario settings recorded in the log metadata."""

    roughness: str | None = None  # ISO 8608 class A-D, or None for a smooth road
    seed: int = 0
    min_wavelength: float = 1.6  # m, bounce-sweep only
    shorten: float = 1.0  # fraction of a lap to drive (tests); 1 = full lap
    grade: float = 0.0  # standstill only: rise over run, > 0 uphill
    bank: float = 0.0  # standstill only: rise over run, > 0 left edge higher
    # brake-in-turn, accel-in-turn only: the speed change beyond the grip (None: the
    # scenario as the paper's checks drive it, within the grip).
    beyond_grip: BeyondGrip | None = field(default=None)
