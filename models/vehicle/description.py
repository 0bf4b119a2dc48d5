"""Vehicle parameters: a frozen, validated description read from a TOML file.

The file layout mirrors the dataclasses below: one table per section, one key
per field. Every key is required (except the optional ``[wheels]``, ``[cornering]``
and ``[plant]`` sections),
unknown keys are rejected, and every error names the file and the key. SI
units; positions relative to the sprung-mass CG in ISO 8855 axes (x forward,
y left, z up).

Reading a file: :func:`wheelload.models.vehicle.file.load_vehicle`.

Example
-------
>>> from wheelload.models.vehicle.file import vehicle_template
>>> vehicle = vehicle_from_dict(tomllib.loads(vehicle_template()))
>>> round(vehicle.mass.total, 1)
1613.2
"""

from __future__ import annotations

import dataclasses
import functools
import math
import sys
import types
import typing
from dataclasses import dataclass

from wheelload.models.vehicle.plant_section import Plant
from wheelload.models.vehicle.section_checks import (
    SectionKeyError,
    require_non_negative,
    require_positive,
    require_share,
)
from wheelload.models.vehicle.sensor_section import Sensors
from wheelload.models.vehicle.wheel_section import Cornering, Wheels

TOTAL_MASS_TOLERANCE = 0.5  # kg, allowed |total - (sprung + unsprung)|


#: Appended to a missing-key error: files written before a section or key existed.
TEMPLATE_HINT = (
    " (files older than this version lack it: print the commented template with "
    "'wheelload vehicle --template' and copy the section with values for your car)"
)


class VehicleFileError(ValueError):
    """A vehicle file that cannot be read: names the file and the key."""


Vector3 = tuple[float, float, float]


@dataclass(frozen=True, kw_only=True)
class Mass:
    """``[mass]``: total, sprung and unsprung masses, sprung-body inertia."""

    total: float  # kg, sprung + unsprung
    sprung: float  # kg
    unsprung_front: float  # kg, both front corners together
    unsprung_rear: float  # kg, both rear corners together
    inertia: Vector3  # kg m^2, (Ixx, Iyy, Izz) of the sprung body about its CG

    def _check(self) -> None:
        for key in ("total", "sprung", "unsprung_front", "unsprung_rear"):
            require_positive(self, key)
        if min(self.inertia) <= 0.0:
            raise SectionKeyError("inertia", f"must be > 0 on every axis, got {self.inertia}")
        parts = self.sprung + self.unsprung_front + self.unsprung_rear
        # The equilibrium uses the total, the plant the parts: they must agree
        # to rounding, or every static load carries the difference.
        if abs(parts - self.total) > TOTAL_MASS_TOLERANCE:
            raise SectionKeyError(
                "total",
                f"is {self.total} kg but sprung + unsprung_front + unsprung_rear = {parts:.1f} kg",
            )


@dataclass(frozen=True, kw_only=True)
class Geometry:
    """``[geometry]``: wheelbase, CG position, tracks, IMU position and orientation."""

    wheelbase: float  # m
    lf: float  # m, sprung CG to front axle
    lr: float  # m, sprung CG to rear axle
    track_front: float  # m
    track_rear: float  # m
    cg_height: float  # m, sprung CG above ground
    imu_position: Vector3  # m, relative to the sprung CG
    imu_orientation: Vector3  # rad, roll, pitch, yaw of the sensor axes in the body axes

    def _check(self) -> None:
        for key in ("wheelbase", "lf", "lr", "track_front", "track_rear", "cg_height"):
            require_positive(self, key)
        if abs(self.lf + self.lr - self.wheelbase) > 0.03 * self.wheelbase:
            raise SectionKeyError(
                "lf",
                f"+ lr = {self.lf + self.lr:.3f} m is more than 3 % away from "
                f"wheelbase = {self.wheelbase} m",
            )


@dataclass(frozen=True, kw_only=True)
class Tyres:
    """``[tyres]``: radii and vertical stiffness per axle."""

    radius_front: float  # m, unloaded
    radius_rear: float  # m
    vertical_stiffness_front: float  # N/m
    vertical_stiffness_rear: float  # N/m

    def _check(self) -> None:
        for field in dataclasses.fields(self):
            require_positive(self, field.name)


@dataclass(frozen=True, kw_only=True)
class Aero:
    """``[aero]``: air density, reference area, lift and drag, application point."""

    air_density: float  # kg/m^3
    reference_area: float  # m^2
    lift_coefficient: float  # -, > 0 is lift
    drag_coefficient: float  # -
    application_point: Vector3  # m, relative to the sprung CG

    def _check(self) -> None:
        require_positive(self, "air_density")
        require_positive(self, "reference_area")
        require_non_negative(self, "drag_coefficient")


@dataclass(frozen=True, kw_only=True)
class AxleSuspension:
    """``[suspension.front]`` or ``[suspension.rear]``: springs, dampers, bar, links, stops."""

    spring_rate: float  # N/m at the wheel
    damper_push: float  # N s/m, compression (v > 0)
    damper_pull: float  # N s/m, rebound (v < 0)
    arb_rate: float  # N/m, anti-roll bar
    arb_ratio: float  # -, gamma_arb of eq. (8)
    roll_centre_height: float  # m, above ground at static ride height
    anti_pitch_brake: float  # -, share of the axle's braking load transfer carried by links
    anti_pitch_drive: float  # -, share of the axle's driving load transfer carried by links
    bump_gap: float  # m, compression from static where the bump stop touches
    rebound_gap: float  # m, extension from static where the rebound stop touches
    stop_rate: float  # N/m, k_1 of the stops: F = k_1 x + k_2 x^2 past the gap
    stop_progressive_rate: float  # N/m^2, k_2

    def _check(self) -> None:
        require_positive(self, "spring_rate")
        for key in (
            "damper_push", "damper_pull", "arb_rate", "arb_ratio", "roll_centre_height",
            "stop_progressive_rate",
        ):  # fmt: skip
            require_non_negative(self, key)
        for key in ("bump_gap", "rebound_gap", "stop_rate"):
            require_positive(self, key)
        for key in ("anti_pitch_brake", "anti_pitch_drive"):
            require_share(self, key)


@dataclass(frozen=True, kw_only=True)
class Suspension:
    """``[suspension]``: both axles and the roll split."""

    front: AxleSuspension
    rear: AxleSuspension
    # Front share of the lateral load transfer (models/roll_split.py); default:
    # the front share of the springs' and bars' roll stiffness, with the
    # roll-centre (link) moments when [model] geometric_transfer is on.
    roll_split_front: float | None = None

    def _check(self) -> None:
        split = self.roll_split_front
        if split is not None and not 0.0 < split < 1.0:
            raise SectionKeyError("roll_split_front", f"must be between 0 and 1, got {split}")


@dataclass(frozen=True, kw_only=True)
class BiasTuning:
    """Slow sensor errors as MHE states: start std, bound, random-walk density."""

    travel_offset_std: float = 0.004  # m
    travel_offset_bound: float = 0.015  # m
    travel_offset_density: float = 1e-9  # m^2/s
    acceleration_bias_std: float = 0.3  # m/s^2
    acceleration_bias_bound: float = 1.5  # m/s^2
    acceleration_bias_density: float = 1e-5  # (m/s^2)^2/s

    def _check(self) -> None:
        for field in dataclasses.fields(self):
            require_positive(self, field.name)


@dataclass(frozen=True, kw_only=True)
class FaultTuning:
    """Smallest sensor faults the fault monitor isolates ([filter.faults], optional).

    Set above what the model's own mismatch looks like on clean logs of the
    vehicle (``wheelload bench faults --alarms-only`` prints that floor per
    channel); defaults: the sports car.
    """

    travel_fault: float = 0.005  # m
    ax_fault: float = 1.2  # m/s^2
    ay_fault: float = 0.3  # m/s^2
    az_fault: float = 1.2  # m/s^2
    # m/s^2: an accelerometer fault estimate that grows with its axis' acceleration is a
    # gain the file has wrong, not a bias; a steady one above this acceleration is taken as
    # a gain (without the split, no bars in the file read as an ay fault on a lane change).
    gain_acceleration: float = 1.0

    def _check(self) -> None:
        for field in dataclasses.fields(self):
            require_positive(self, field.name)


#: The reported-sigma model's coefficients ([filter], optional), in feature order
#: (estimators/kf/reported_std.py).
SIGMA_KEYS = (
    "sigma_covariance",
    "sigma_floor",
    "sigma_ax",
    "sigma_ay",
    "sigma_travel_rate",
    "sigma_travel",
    "sigma_residual",
    "sigma_residual_rms",
    "sigma_innovation",
    "sigma_innovation_rms",
    "sigma_no_travel",
    "sigma_no_travel_ax",
    "sigma_no_travel_ay",
    "sigma_no_travel_az",
    "sigma_no_travel_lateral",
)


@dataclass(frozen=True, kw_only=True)
class PayloadTuning:
    """Online payload mass and CG ([filter.payload], optional; estimators/kf/payload.py).

    ``travel_from_reference``: the travel sensors read 0 in the file's reference state
    (its masses, on level ground), so a payload shows as static compression; false when
    the logger zeroes the travel at the start of a log (a payload is then invisible to
    the springs and is not estimated: give measured static loads, ``--corner-weights``).
    """

    estimate: bool = True
    travel_from_reference: bool = True
    mass_std: float = 300.0  # kg, prior std of the payload mass
    # m, prior std of its position about the CG. Height 0: not estimated (the payload sits at
    # the CG's height): in the moment rows a CG-height error looks like a spring-rate error,
    # and learning it turns a 20 % spring error into a CG error (Hockenheim 172 -> 213 N);
    # set it (e.g. 0.3) for a known suspension and a high load (roof box).
    position_std: Vector3 = (1.0, 0.5, 0.0)
    residual_density: Vector3 = (3.0e4, 3.0e4, 2.0e4)  # N^2 s, N^2 m^2 s, N^2 m^2 s
    drift_density: float = 0.01  # kg^2/s, random walk of the mass while driving
    standstill_density: float = 500.0  # kg^2/s, random walk while standing (loading)
    standstill_speed: float = 0.5  # m/s, |vx| below which the car is standing
    gate: float = 16.0  # chi^2_1 threshold of a residual row (4 sigma)
    # m/s^2 per row: residual density x (1 + a^2 / a_s^2)^2 with a^2 = ax^2 + ay^2 (vertical
    # row), ax^2 (pitch), ay^2 (roll). The vertical row's mismatch hardly grows in a turn
    # (on the bundled cars' logs its spread is 25-140 N at every |a|), so the mass is
    # weighed in turns too; a moment row's grows with its own load transfer and is
    # coloured (a steady turn is one long sample of it).
    acceleration_scale: Vector3 = (5.0, 1.5, 1.5)
    # The payload that the sensors' own errors make appear (kg; kg m for S_x, S_y): an
    # accelerometer bias of 0.1 m/s^2 on a 1600 kg car reads as 16 kg, 0.05 m/s^2 in ax or
    # ay as 4 kg m, travel sensors 0.5 mm apart front to rear as 5-10 kg m. The loads take
    # an estimate weighted by its evidence, theta^2 / (theta^2 + apparent^2), so a sensor
    # error is not learnt as a changed car.
    apparent_mass: float = 15.0
    apparent_moment: float = 10.0

    def _check(self) -> None:
        for key in ("mass_std", "drift_density", "standstill_density", "standstill_speed",
                    "gate", "apparent_mass",
                    "apparent_moment"):  # fmt: skip
            require_positive(self, key)
        for key in ("residual_density", "acceleration_scale"):
            if min(getattr(self, key)) <= 0.0:
                raise SectionKeyError(key, "must be > 0 in every entry")
        if min(self.position_std) < 0.0 or min(self.position_std[:2]) == 0.0:
            raise SectionKeyError(
                "position_std", "must be > 0 in x and y and >= 0 in z (0: height not estimated)"
            )


@dataclass(frozen=True, kw_only=True)
class FilterTuning:
    """``[filter]``: the KF's noise densities, initial std and the online payload."""

    process_noise_density: float  # N^2/s:  Q = q dt I
    suspension_noise_density: float  # N^2 s: Rs = r_s / dt I
    constraint_noise_density: Vector3  # [N^2 s, N^2 m^2 s, N^2 m^2 s]: Rc = diag(r_c) / dt
    initial_std: float  # N
    bias: BiasTuning = BiasTuning()  # [filter.bias], optional: MHE bias states
    faults: FaultTuning = FaultTuning()  # [filter.faults], optional: fault-monitor limits
    payload: PayloadTuning = PayloadTuning()  # [filter.payload], optional: online mass and CG
    # Optional: the innovation variance S the gate compares against (estimators/guards/settings.py,
    # innovation_variance_scale) times this factor. ``wheelload tune`` writes 1/c when it
    # scales the densities by c to calibrate sigma, so that the gate keeps the decisions it
    # had (S scales by c, the innovations do not).
    gate_scale: float = 1.0
    # Optional: the body-rate derivative filter's jerk density q [(rad/s^3)^2/Hz]
    # (estimators/logs/signals.py, RateDerivativeFilter), from plant logs at 100-1000 Hz:
    # 0.1 lags the bounce sweep's body motion (sports car 62 -> 104 N), 10 lets the gyro
    # noise in at rest. Its measurement noise is [sensors] gyro_noise_density's.
    rate_jerk_density: float = 1.0
    # Optional: input-dependent measurement noise (models/measurement_noise.py), default 0
    # (constant R). N^2 s per (m/s)^2 of damper velocity, per (m/s^2)^2 of hub acceleration
    # relative to the body; vertical, pitch, roll rows per (m/s^2)^2 of az - g, ax, ay.
    suspension_noise_rate_density: float = 0.0
    suspension_noise_hub_density: float = 0.0
    constraint_noise_acceleration_density: Vector3 = (0.0, 0.0, 0.0)
    # Optional: the reported-sigma model (estimators/kf/reported_std.py), sigma^2 =
    # sum_k (c_k g_ik)^2 with g_i0 = sqrt(P_ii); the gain does not see it. Defaults:
    # calibrated by ``wheelload study sigma`` on the bundled vehicles' scenarios;
    # ``wheelload tune`` writes those of its logs.
    sigma_covariance: float = 0.05034  # per N of sqrt(P_ii), the filter's own sigma
    sigma_floor: float = 16.42  # N
    sigma_ax: float = 1.64  # N per m/s^2 of |ax|
    sigma_ay: float = 4.984  # N per m/s^2 of |ay|
    sigma_travel_rate: float = 1968  # N per m/s of |v_i| (damper)
    sigma_travel: float = 135  # N per m of |d_i| (spring)
    sigma_residual: float = 0.3402  # per N of the equilibrium residual at z, per wheel
    sigma_residual_rms: float = 0.0006823  # per N of its running RMS
    sigma_innovation: float = 0.3238  # per N of |suspension innovation|
    sigma_innovation_rms: float = 0.0005492  # per N of its running RMS
    # A wheel without its suspension row (no travel: from the equilibrium and the split).
    # Fitted (``wheelload bench discernment --fit-no-travel``: the likelihood, the pooled
    # 95 % scale, each log into 91-98 % where the features allow; the other keys held) on
    # both bundled cars' scenarios at both sensor grades with the travel columns dropped,
    # once as logged and once with the rear references removed and ``ay`` 0.5 s late (a
    # front-only reference log of a real car, whose ay lags the loads).
    sigma_no_travel: float = 58.59  # N
    sigma_no_travel_ax: float = 33.58  # N per m/s^2 of |ax|
    sigma_no_travel_ay: float = 2.056  # N per m/s^2 of |ay|
    sigma_no_travel_az: float = 307.7  # N per m/s^2 of |az - g| (heave, pitch)
    sigma_no_travel_lateral: float = 873.8  # N per m/s^2 of |ay - vx wz| (lag, bank, slip)

    def sigma_model(self) -> tuple[float, ...]:
        """The reported-sigma coefficients in :data:`SIGMA_KEYS` order."""
        return tuple(getattr(self, key) for key in SIGMA_KEYS)

    def input_densities(self) -> tuple[float, ...]:
        """The input-dependent densities in ``measurement_noise.INPUT_DENSITIES`` order."""
        return (
            self.suspension_noise_rate_density,
            self.suspension_noise_hub_density,
            *self.constraint_noise_acceleration_density,
        )

    def _check(self) -> None:
        for key in (
            "suspension_noise_rate_density",
            "suspension_noise_hub_density",
            "constraint_noise_acceleration_density",
        ):
            values = getattr(self, key)
            values = values if isinstance(values, tuple) else (values,)
            if not all(math.isfinite(x) and x >= 0.0 for x in values):
                raise SectionKeyError(
                    key, f"must be finite and >= 0 (0: constant noise), got {values}"
                )
        for key in SIGMA_KEYS:
            require_non_negative(self, key)
        require_positive(self, "process_noise_density")
        require_positive(self, "suspension_noise_density")
        require_positive(self, "initial_std")
        require_positive(self, "gate_scale")
        require_positive(self, "rate_jerk_density")
        if min(self.constraint_noise_density) <= 0.0:
            raise SectionKeyError("constraint_noise_density", "must be > 0 in every row")


@dataclass(frozen=True, kw_only=True)
class ModelTerms:
    """Switches of the model terms beyond the paper (all false: the paper's model).

    See ``wheelload.models.terms`` for what each term adds.
    """

    road_frame: bool  # equilibrium in the road frame (body roll/pitch from the travel)
    body_inertia: bool  # I_xx p_dot, I_yy q_dot in the moment rows (needs body rates)
    geometric_transfer: bool  # roll-centre and anti-pitch load through the links
    stops: bool  # bump and rebound stops in the pseudo-measurement
    unsprung_inertia: bool  # m_u a_hub per corner (needs hub accelerometers)
    imu_lever_arm: bool  # specific force moved from the IMU to the CG (needs body rates)

    def _check(self) -> None:
        pass


@dataclass(frozen=True, kw_only=True)
class Vehicle:
    """A vehicle: mass, geometry, tyres, aerodynamics, suspension, model terms, filter tuning."""

    name: str
    description: str
    mass: Mass
    geometry: Geometry
    tyres: Tyres
    aero: Aero
    suspension: Suspension
    model: ModelTerms
    filter: FilterTuning
    wheels: Wheels | None = None  # the tyre-force estimators (models/vehicle/wheel_section.py)
    cornering: Cornering | None = None  # their left/right split, beyond the paper
    sensors: Sensors = Sensors()  # the logged sensors' noise (models/vehicle/sensor_section.py)
    plant: Plant | None = None  # ground-truth simulator only (models/vehicle/plant_section.py)

    def _check(self) -> None:
        pass

    def replace(self, **changes: object) -> Vehicle:
        """A copy with whole sections replaced, validated again."""
        new = dataclasses.replace(self, **changes)
        _validate(new, "")
        return new


def _validate(obj: object, prefix: str) -> None:
    for field in dataclasses.fields(obj):  # type: ignore[arg-type]
        value = getattr(obj, field.name)
        if dataclasses.is_dataclass(value):
            _validate(value, f"{prefix}{field.name}.")
    try:
        obj._check()  # type: ignore[attr-defined]
    except SectionKeyError as error:
        raise VehicleFileError(f"key '{prefix}{error.key}' {error}") from None


def _convert(value: object, kind: object, key: str) -> object:
    """Convert one TOML value to the annotated field type, or raise naming the key."""
    if kind is str:
        if not isinstance(value, str):
            raise VehicleFileError(f"key '{key}' must be a string, got {value!r}")
        return value
    if kind is bool:
        if not isinstance(value, bool):
            raise VehicleFileError(f"key '{key}' must be true or false, got {value!r}")
        return value
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise VehicleFileError(f"key '{key}' must be a number, got {value!r}")
        if not math.isfinite(value):
            raise VehicleFileError(f"key '{key}' must be finite, got {value!r}")
        return float(value)
    if typing.get_origin(kind) is tuple:
        items = typing.get_args(kind)
        if not isinstance(value, list) or len(value) != len(items):
            raise VehicleFileError(f"key '{key}' must be a list of {len(items)} numbers")
        return tuple(_convert(v, t, f"{key}[{i}]") for i, (v, t) in enumerate(zip(value, items)))
    if isinstance(kind, type) and dataclasses.is_dataclass(kind):
        if not isinstance(value, dict):
            raise VehicleFileError(f"key '{key}' must be a table [{key}]")
        return _build(kind, value, f"{key}.")
    if isinstance(kind, types.UnionType) and value is None:
        return None
    if isinstance(kind, types.UnionType):
        (inner,) = [t for t in typing.get_args(kind) if t is not type(None)]
        return _convert(value, inner, key)
    raise TypeError(f"unsupported field type {kind} for key '{key}'")


@functools.cache
def field_types(cls: type) -> dict[str, object]:
    """``typing.get_type_hints`` of a dataclass of the vehicle file: each field's annotation
    evaluated in the class's module, each annotation's text once (a vehicle file has about
    130 fields, most of them ``float``)."""
    fields = dataclasses.fields(cls)
    return {field.name: _annotation(field.type, cls.__module__) for field in fields}


@functools.cache
def _annotation(text: str, module: str) -> object:
    return eval(text, vars(sys.modules[module]))  # our own annotations, as get_type_hints


def _build(cls: type, table: dict, prefix: str) -> object:
    hints = field_types(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(table) - set(fields))
    if unknown:
        raise VehicleFileError(f"unknown key '{prefix}{unknown[0]}'")
    sections = [
        name
        for name, field in fields.items()
        if dataclasses.is_dataclass(hints[name])
        and field.default is dataclasses.MISSING
        and name not in table
    ]
    if sections:  # a whole missing section first: the usual sign of an older file
        raise VehicleFileError(f"missing section [{prefix}{sections[0]}]{TEMPLATE_HINT}")
    values = {}
    for name, field in fields.items():
        if name not in table:
            if field.default is not dataclasses.MISSING:
                continue
            what = (
                f"section [{prefix}{name}]"
                if dataclasses.is_dataclass(hints[name])
                else f"key '{prefix}{name}'"
            )
            raise VehicleFileError(f"missing {what}{TEMPLATE_HINT}")
        values[name] = _convert(table[name], hints[name], f"{prefix}{name}")
    return cls(**values)


def field_default(key: tuple[str, ...]) -> object:
    """The dataclass default of the vehicle-file key ``key`` (its table's parts, then
    the key)."""
    cls: type = Vehicle
    *parents, name = key
    for part in parents:
        cls = field_types(cls)[part]  # type: ignore[assignment]
    (field,) = [f for f in dataclasses.fields(cls) if f.name == name]
    return field.default


def vehicle_from_dict(table: dict) -> Vehicle:
    """Build and validate a :class:`Vehicle` from a parsed TOML table; the defaults that
    scale with the car are its own (:mod:`~wheelload.models.vehicle.scaled_defaults`)."""
    from wheelload.models.vehicle.scaled_defaults import MASS_POWERS, with_scaled_defaults

    table = with_scaled_defaults(table, {key: field_default(key) for key in MASS_POWERS})
    vehicle = _build(Vehicle, table, "")
    _validate(vehicle, "")
    return vehicle  # type: ignore[return-value]
