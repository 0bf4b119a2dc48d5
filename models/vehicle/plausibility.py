r"""Physical plausibility of a vehicle file: an accepted interval for every key.

:func:`check_vehicle_ranges` returns every key whose value lies outside the
interval the physics of a road vehicle allows; :func:`load_vehicle` refuses
such a file unless ``allow_unusual`` (``--allow-unusual``). Intervals that
depend on other keys:

- CG height against the track: static stability factor :math:`T/(2h) \ge 0.6`
  (below it the car rolls over before it slides, even for a truck);
- ``lf`` and ``lr`` between 15 % and 85 % of the wheelbase;
- tyre vertical stiffness against the static wheel load :math:`W`: static
  tyre deflection :math:`W/k_t` between 3 and 60 mm;
- spring rate against the sprung corner mass :math:`m_c`: ride frequency
  :math:`\sqrt{k/m_c}/2\pi` between 0.5 and 5 Hz; dampers up to a damping
  ratio of 3; anti-roll bar up to 10 times the spring;
- filter tuning against the static wheel load and the vehicle weight
  (1-sigma from 1 N up to ten times the weight at 100 Hz).

Example
-------
>>> check_vehicle_ranges(load_vehicle(example_vehicle_path()))
[]
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.mass_properties import static_loads
from wheelload.models.vehicle.description import Vehicle, field_types

TUNING_RATE = 100.0  # Hz, the sample rate at which tuning sigmas are judged


@dataclass(frozen=True)
class Range:
    """Accepted closed interval ``[low, high]`` of a key, and where it comes from."""

    low: float
    high: float
    reason: str

    def holds(self, value: float) -> bool:
        return bool(self.low <= value <= self.high) or not (
            math.isfinite(self.low) and math.isfinite(self.high)
        )


@dataclass(frozen=True)
class Violation:
    """A key whose value is outside its plausible range."""

    key: str
    value: float
    range: Range

    def __str__(self) -> str:
        return (
            f"key '{self.key}' = {self.value:.4g} is outside the accepted "
            f"[{self.range.low:.4g}, {self.range.high:.4g}] ({self.range.reason})"
        )


def _corner_masses(v: Vehicle) -> tuple[float, float]:
    """Sprung mass per corner, front and rear [kg] (lever rule on the sprung CG)."""
    g = v.geometry
    base = g.lf + g.lr
    return v.mass.sprung * g.lr / base / 2.0, v.mass.sprung * g.lf / base / 2.0


def _wheel_loads(v: Vehicle) -> tuple[float, float]:
    with np.errstate(all="ignore"):
        loads = static_loads(v)
    return float(loads[0]), float(loads[2])


def _fixed(low: float, high: float, reason: str) -> Callable[[Vehicle], Range]:
    return lambda v: Range(low, high, reason)


def _share(low: float, high: float, of: Callable[[Vehicle], float], reason: str):
    return lambda v: Range(low * of(v), high * of(v), reason)


def _spring(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        m = _corner_masses(v)[axle]
        return Range((2 * math.pi * 0.5) ** 2 * m, (2 * math.pi * 5.0) ** 2 * m,
                     "ride frequency 0.5-5 Hz on the sprung corner mass")  # fmt: skip

    return rule


def _damper(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        k = (v.suspension.front, v.suspension.rear)[axle].spring_rate
        return Range(0.0, 3.0 * 2.0 * math.sqrt(k * _corner_masses(v)[axle]),
                     "damping ratio 0-3 on the spring and sprung corner mass")  # fmt: skip

    return rule


def _arb(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        k = (v.suspension.front, v.suspension.rear)[axle].spring_rate
        return Range(0.0, 10.0 * k, "0-10 times the axle's spring rate")

    return rule


def _tyre(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        load = _wheel_loads(v)[axle]
        return Range(load / 0.060, load / 0.003,
                     "static tyre deflection 3-60 mm under the static wheel load")  # fmt: skip

    return rule


def _weight(v: Vehicle) -> float:
    return v.mass.total * GRAVITY


def _sigma_density(low: Callable[[Vehicle], float], high: Callable[[Vehicle], float], what: str):
    """Noise density r with 1-sigma sqrt(r * rate) (or sqrt(r / dt)) in [low, high]."""

    def rule(v: Vehicle) -> Range:
        reason = f"1 sigma {low(v):.3g}-{high(v):.3g} {what} at {TUNING_RATE:.0f} Hz"
        return Range(low(v) ** 2 / TUNING_RATE, high(v) ** 2 / TUNING_RATE, reason)

    return rule


def _process(v: Vehicle) -> Range:
    wheel = max(_wheel_loads(v))
    reason = "load random walk 1 % to 1000 x the static wheel load per root second"
    return Range((0.01 * wheel) ** 2, (1000.0 * wheel) ** 2, reason)


def _position(v: Vehicle) -> tuple[Range, Range, Range]:
    g = v.geometry
    reach = max(g.lf, g.lr) + 1.0
    half = 0.5 * max(g.track_front, g.track_rear) + 0.5
    return (Range(-reach, reach, "within 1 m of the wheelbase"),
            Range(-half, half, "within 0.5 m of the track"),
            Range(-g.cg_height, 2.0, "between the ground and 2 m above the CG"))  # fmt: skip


def _body_width(v: Vehicle) -> Range:
    track = max(v.geometry.track_front, v.geometry.track_rear)
    return Range(track, track + 1.0, "at least the track, at most 1 m wider")


def _spin(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        m = (v.mass.unsprung_front, v.mass.unsprung_rear)[axle] / 2.0
        r = (v.tyres.radius_front, v.tyres.radius_rear)[axle]
        return Range(0.05 * m * r**2, 1.0 * m * r**2,
                     "0.05-1 x corner unsprung mass x tyre radius^2")  # fmt: skip

    return rule


def _nominal(axle: int) -> Callable[[Vehicle], Range]:
    def rule(v: Vehicle) -> Range:
        load = _wheel_loads(v)[axle]
        return Range(0.3 * load, 3.0 * load, "0.3-3 x the static wheel load")

    return rule


def _cg_height(v: Vehicle) -> Range:
    track = min(v.geometry.track_front, v.geometry.track_rear)
    return Range(0.1, track / (2 * 0.6), "static stability factor track / (2 h) >= 0.6")


def _roll_centre(v: Vehicle) -> Range:
    return Range(0.0, v.geometry.cg_height, "from the ground to the CG height")


def _inertia(v: Vehicle) -> Range:
    return Range(0.04 * v.mass.sprung, 9.0 * v.mass.sprung,
                 "radius of gyration 0.2-3 m on the sprung mass")  # fmt: skip


#: Accepted interval of every key of a vehicle file (a tuple-valued key: one per element,
#: or one for all of them).
RANGES: dict[str, Callable[[Vehicle], Range | tuple[Range, ...]]] = {
    "mass.total": _fixed(200.0, 50_000.0, "road vehicles from a microcar to a heavy truck"),
    "mass.sprung": _share(0.6, 0.97, lambda v: v.mass.total, "60-97 % of the total mass"),
    "mass.unsprung_front": _share(0.02, 0.25, lambda v: v.mass.total, "2-25 % of the total"),
    "mass.unsprung_rear": _share(0.02, 0.25, lambda v: v.mass.total, "2-25 % of the total"),
    "geometry.wheelbase": _fixed(1.0, 8.0, "road vehicles"),
    "geometry.lf": _share(0.15, 0.85, lambda v: v.geometry.wheelbase, "15-85 % of the wheelbase"),
    "geometry.lr": _share(0.15, 0.85, lambda v: v.geometry.wheelbase, "15-85 % of the wheelbase"),
    "geometry.track_front": _fixed(0.8, 2.6, "road vehicles"),
    "geometry.track_rear": _fixed(0.8, 2.6, "road vehicles"),
    "geometry.cg_height": _cg_height,
    "geometry.imu_position": _position,
    "tyres.radius_front": _fixed(0.15, 0.7, "road tyres"),
    "tyres.radius_rear": _fixed(0.15, 0.7, "road tyres"),
    "tyres.vertical_stiffness_front": _tyre(0),
    "tyres.vertical_stiffness_rear": _tyre(1),
    "aero.air_density": _fixed(0.5, 1.5, "air from 5000 m altitude to -40 degC"),
    "aero.reference_area": _fixed(0.5, 15.0, "frontal areas of road vehicles"),
    "aero.lift_coefficient": _fixed(-3.5, 1.0, "from a race car's downforce to a lifting body"),
    "aero.drag_coefficient": _fixed(0.15, 1.5, "road vehicles"),
    "aero.application_point": _position,
    "suspension.front.spring_rate": _spring(0),
    "suspension.rear.spring_rate": _spring(1),
    "suspension.front.damper_push": _damper(0),
    "suspension.front.damper_pull": _damper(0),
    "suspension.rear.damper_push": _damper(1),
    "suspension.rear.damper_pull": _damper(1),
    "suspension.front.arb_rate": _arb(0),
    "suspension.rear.arb_rate": _arb(1),
    "suspension.front.arb_ratio": _fixed(0.0, 3.0, "installation ratio of a bar"),
    "suspension.rear.arb_ratio": _fixed(0.0, 3.0, "installation ratio of a bar"),
    "suspension.roll_split_front": _fixed(0.15, 0.85, "front share of the lateral load transfer"),
    **{
        f"suspension.{axle}.{key}": rule
        for axle in ("front", "rear")
        for key, rule in (
            ("roll_centre_height", _roll_centre),
            ("anti_pitch_brake", _fixed(0.0, 1.0, "a share of the rigid transfer (0-100 % anti)")),
            ("anti_pitch_drive", _fixed(0.0, 1.0, "a share of the rigid transfer (0-100 % anti)")),
            ("bump_gap", _fixed(0.003, 0.2, "bump-stop gaps of road cars")),
            ("rebound_gap", _fixed(0.01, 0.3, "droop travel of road cars")),
            ("stop_rate", _fixed(1e3, 1e7, "elastomer bump stops")),
            ("stop_progressive_rate", _fixed(0.0, 1e9, "elastomer bump stops")),
        )
    },
    "mass.inertia": _inertia,
    "geometry.imu_orientation": _fixed(-math.pi, math.pi, "angles of the sensor axes [rad]"),
    **{
        f"model.{switch}": _fixed(0.0, 1.0, "a switch: false or true")
        for switch in (
            "road_frame",
            "body_inertia",
            "geometric_transfer",
            "stops",
            "unsprung_inertia",
            "imu_lever_arm",
        )
    },
    "filter.process_noise_density": _process,
    "filter.suspension_noise_density": _sigma_density(
        lambda v: 1.0, lambda v: 10.0 * max(_wheel_loads(v)), "N"
    ),
    "filter.constraint_noise_density": _sigma_density(
        lambda v: 1.0, lambda v: 10.0 * _weight(v), "N (N m)"
    ),
    # Input-dependent noise (models/measurement_noise.py): 0 (constant R) up to the range's
    # 1-sigma ceiling reached at 1 m/s of damper velocity or 1 g of acceleration.
    "filter.suspension_noise_rate_density": _sigma_density(
        lambda v: 0.0, lambda v: 10.0 * max(_wheel_loads(v)), "N at 1 m/s damper velocity,"
    ),
    "filter.suspension_noise_hub_density": _sigma_density(
        lambda v: 0.0, lambda v: 10.0 * max(_wheel_loads(v)) / GRAVITY, "N at 1 m/s^2 hub,"
    ),
    "filter.constraint_noise_acceleration_density": _sigma_density(
        lambda v: 0.0, lambda v: 10.0 * _weight(v) / GRAVITY, "N (N m) at 1 m/s^2,"
    ),
    "filter.initial_std": lambda v: Range(1.0, 10.0 * _weight(v), "1 N to 10 x the weight"),
    "filter.gate_scale": _fixed(
        1e-4, 1e4, "factor on the innovation variance the gate compares against"
    ),
    # The body-rate derivative filter (estimators/logs/signals.py): 0.1 lags the bounce
    # sweep's body motion, 10 lets an MTi-1 gyroscope's noise in at rest.
    "filter.rate_jerk_density": _fixed(1e-3, 1e3, "jerk density of body rates, (rad/s^3)^2/Hz"),
    "sensors.gyro_noise_density": _fixed(
        1e-6, 1e-2, "gyroscopes' noise densities, 0.00006-0.6 deg/s/sqrt(Hz), in rad/s/sqrt(Hz)"
    ),
    "filter.bias.travel_offset_std": _fixed(1e-4, 0.05, "0.1-50 mm of travel-sensor offset"),
    "filter.bias.travel_offset_bound": _fixed(1e-3, 0.1, "1-100 mm of travel-sensor offset"),
    "filter.bias.travel_offset_density": _fixed(1e-14, 1e-4, "travel offset random walk, m^2/s"),
    "filter.bias.acceleration_bias_std": _fixed(1e-3, 5.0, "accelerometer bias up to 0.5 g"),
    "filter.bias.acceleration_bias_bound": _fixed(0.01, 10.0, "accelerometer bias up to 1 g"),
    "filter.faults.travel_fault": _fixed(1e-4, 0.05, "0.1-50 mm of travel-sensor fault"),
    "filter.faults.ax_fault": _fixed(0.01, 10.0, "an ax fault of 0.01 m/s^2 to 1 g"),
    "filter.faults.ay_fault": _fixed(0.01, 10.0, "an ay fault of 0.01 m/s^2 to 1 g"),
    "filter.faults.az_fault": _fixed(0.01, 10.0, "an az fault of 0.01 m/s^2 to 1 g"),
    "filter.faults.gain_acceleration": _fixed(0.01, 20.0, "0.01-20 m/s^2"),
    "filter.bias.acceleration_bias_density": _fixed(
        1e-12, 1.0, "accelerometer bias random walk, (m/s^2)^2/s"
    ),
    # The reported sigma's coefficients (estimators/kf/reported_std.py): 0 switches a term off.
    "filter.sigma_covariance": _fixed(0.0, 10.0, "0-10 x the filter's own sigma"),
    "filter.sigma_floor": lambda v: Range(0.0, _weight(v), "0 N to the weight"),
    "filter.sigma_ax": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2 of |ax|"),
    "filter.sigma_ay": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2 of |ay|"),
    "filter.sigma_travel_rate": lambda v: Range(
        0.0, 10.0 * max(_wheel_loads(v)), "0-10 x the static wheel load per m/s of damper"
    ),
    "filter.sigma_travel": lambda v: Range(
        0.0, 1000.0 * max(_wheel_loads(v)), "0-1000 x the static wheel load per m of travel"
    ),
    **{
        f"filter.sigma_{name}": _fixed(0.0, 10.0, "0-10 per N of the model's mismatch")
        for name in ("residual", "residual_rms", "innovation", "innovation_rms")
    },
    "filter.sigma_no_travel": lambda v: Range(0.0, _weight(v), "0 N to the weight"),
    "filter.sigma_no_travel_ax": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2"),
    "filter.sigma_no_travel_ay": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2"),
    "filter.sigma_no_travel_az": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2"),
    "filter.sigma_no_travel_lateral": lambda v: Range(0.0, v.mass.total, "0 to m N per m/s^2"),
    # The payload filter (estimators/kf/payload.py).
    "filter.payload.estimate": _fixed(0.0, 1.0, "a switch: false or true"),
    "filter.payload.travel_from_reference": _fixed(0.0, 1.0, "a switch: false or true"),
    "filter.payload.mass_std": lambda v: Range(1.0, v.mass.total, "1 kg to the vehicle's mass"),
    "filter.payload.position_std": _fixed(0.0, 5.0, "0-5 m about the CG"),
    "filter.payload.residual_density": _sigma_density(
        lambda v: 1.0, lambda v: 10.0 * _weight(v), "N (N m)"
    ),
    "filter.payload.drift_density": _fixed(1e-9, 1e4, "mass random walk while driving, kg^2/s"),
    "filter.payload.standstill_density": _fixed(1e-6, 1e6, "mass random walk at a stop, kg^2/s"),
    "filter.payload.standstill_speed": _fixed(0.01, 5.0, "0.01-5 m/s"),
    "filter.payload.gate": _fixed(1.0, 1e4, "chi^2_1 threshold, 1-100 sigma"),
    "filter.payload.acceleration_scale": _fixed(0.1, 50.0, "0.1-50 m/s^2"),
    "filter.payload.apparent_mass": lambda v: Range(
        0.01, 0.2 * v.mass.total, "0.01 kg to 20 % of m"
    ),
    "filter.payload.apparent_moment": lambda v: Range(
        0.01, 0.1 * v.mass.total, "0.01 to 0.1 m kg m"
    ),
    "wheels.spin_inertia_front": _spin(0),
    "wheels.spin_inertia_rear": _spin(1),
    "wheels.rolling_resistance": _fixed(0.0, 0.05, "road tyres"),
    "cornering.nominal_load_front": _nominal(0),
    "cornering.nominal_load_rear": _nominal(1),
    "cornering.friction": _fixed(0.1, 3.0, "ice to racing slicks"),
    "cornering.friction_load_sensitivity": _fixed(-0.5, 0.1, "magic-formula p_D2"),
    "cornering.cornering_load": _fixed(0.5, 5.0, "p_Ky2 of road tyres"),
    "plant.body.width": _body_width,
    "plant.wheels.spin_inertia_front": _spin(0),
    "plant.wheels.spin_inertia_rear": _spin(1),
    "plant.tyre.nominal_load_front": _nominal(0),
    "plant.tyre.nominal_load_rear": _nominal(1),
    "plant.tyre.friction_x": _fixed(0.1, 3.0, "ice to racing slicks"),
    "plant.tyre.friction_y": _fixed(0.1, 3.0, "ice to racing slicks"),
    "plant.tyre.friction_load_sensitivity": _fixed(-0.5, 0.1, "magic-formula p_D2"),
    "plant.tyre.shape_x": _fixed(1.0, 2.0, "magic-formula C"),
    "plant.tyre.shape_y": _fixed(1.0, 2.0, "magic-formula C"),
    "plant.tyre.curvature_x": _fixed(-10.0, 1.0, "magic-formula E <= 1"),
    "plant.tyre.curvature_y": _fixed(-10.0, 1.0, "magic-formula E <= 1"),
    "plant.tyre.slip_stiffness_x": _fixed(5.0, 60.0, "K_x / F_z of road tyres"),
    "plant.tyre.cornering_stiffness_y": _fixed(5.0, 60.0, "p_Ky1 of road tyres"),
    "plant.tyre.cornering_load_y": _fixed(0.5, 5.0, "p_Ky2 of road tyres"),
    "plant.tyre.relaxation_length_x": _fixed(0.02, 2.0, "0.1-5 x a tyre radius"),
    "plant.tyre.relaxation_length_y": _fixed(0.02, 2.0, "0.1-5 x a tyre radius"),
    "plant.tyre.rolling_resistance": _fixed(0.0, 0.05, "road tyres"),
    "plant.dampers.front.velocities": _fixed(0.01, 10.0, "damper test velocities"),
    "plant.dampers.front.push": lambda v: Range(0.0, 10.0 * _weight(v), "up to 10 x the weight"),
    "plant.dampers.front.pull": lambda v: Range(0.0, 10.0 * _weight(v), "up to 10 x the weight"),
    "plant.dampers.rear.velocities": _fixed(0.01, 10.0, "damper test velocities"),
    "plant.dampers.rear.push": lambda v: Range(0.0, 10.0 * _weight(v), "up to 10 x the weight"),
    "plant.dampers.rear.pull": lambda v: Range(0.0, 10.0 * _weight(v), "up to 10 x the weight"),
    "plant.driveline.max_power": _fixed(5e3, 2e6, "5 kW to 2 MW at the wheels"),
    "plant.driveline.drive_share_front": _fixed(0.0, 1.0, "a share"),
    "plant.driveline.brake_share_front": _fixed(0.0, 1.0, "a share"),
    "plant.roughness.reference_frequency": _fixed(0.01, 1.0, "ISO 8608 n0 = 0.1 cycle/m"),
    "plant.roughness.waviness": _fixed(1.0, 4.0, "ISO 8608 w = 2"),
    "plant.roughness.class_psd": _fixed(1e-7, 0.1, "ISO 8608 classes A-H in m^3"),
    "plant.roughness.band": _fixed(0.001, 20.0, "spatial frequencies in cycles/m"),
    "plant.roughness.enveloping_length": _fixed(0.01, 0.5, "tyre contact lengths"),
}


def vehicle_keys(cls: type = Vehicle, prefix: str = "") -> list[str]:
    """Every numeric key of a vehicle file, dotted (``geometry.cg_height``)."""
    import typing

    keys = []
    hints = field_types(cls)
    for field in dataclasses.fields(cls):
        kind = hints[field.name]
        if isinstance(kind, typing.types.UnionType):  # type: ignore[attr-defined]
            (kind,) = [t for t in typing.get_args(kind) if t is not type(None)]
        if isinstance(kind, type) and dataclasses.is_dataclass(kind):
            keys += vehicle_keys(kind, f"{prefix}{field.name}.")
        elif kind is not str:
            keys.append(f"{prefix}{field.name}")
    return keys


def _value(vehicle: Vehicle, key: str) -> object:
    value: object = vehicle
    for part in key.split("."):
        value = None if value is None else getattr(value, part)
    return value


def range_checks(vehicle: Vehicle):
    """``(name, value, accepted)`` of every key the file gives, against its accepted interval
    (:data:`RANGES`; a tuple key once per element, ``key[k]``; optional keys only if given)."""
    for key, rule in RANGES.items():
        value = _value(vehicle, key)
        if value is None:  # an optional key or section left out
            continue
        values = value if isinstance(value, tuple) else (value,)
        ranges = rule(vehicle)
        ranges = ranges if isinstance(ranges, tuple) else (ranges,) * len(values)
        for k, (item, accepted) in enumerate(zip(values, ranges)):
            name = f"{key}[{k}]" if isinstance(value, tuple) else key
            yield name, float(item), accepted  # type: ignore[arg-type]


def check_vehicle_ranges(vehicle: Vehicle) -> list[Violation]:
    """Every key outside its accepted interval (:data:`RANGES`); optional keys only if given."""
    return [
        Violation(name, value, accepted)
        for name, value, accepted in range_checks(vehicle)
        if not accepted.holds(value)
    ]
