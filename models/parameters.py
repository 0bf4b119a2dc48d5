"""The model parameter vector: one ordered layout shared by every CasADi function.

Every symbolic model takes its parameters as an explicit vector ``p`` so that
the same function serves the Python filter (numeric ``p``), generated C with
runtime parameters, and identification (Jacobians with respect to ``p``).

Some parameters are derived from others (:data:`DERIVED`: the static loads from the mass
and CG, the default roll split from the springs, bars and links): one CasADi Function,
:func:`derived_function`, gives them, for :meth:`ModelParameters.from_vehicle` and for the
generated C, which evaluates it again when one of their sources is set at run time.

Example
-------
>>> p = ModelParameters.from_vehicle(load_vehicle(example_vehicle_path()))
>>> p.vector().shape
(68,)
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from wheelload.models.mass_properties import level_static_loads, vehicle_mass_centre
from wheelload.models.runtime.function_cache import stored_function
from wheelload.models.runtime.function_library import compiled_function
from wheelload.models.vehicle.description import Vehicle

#: Per-axle parameters ``<name>_front``, ``<name>_rear`` and their
#: :class:`~wheelload.models.vehicle.description.AxleSuspension` keys.
AXLE_KEYS = {
    "spring": "spring_rate",
    "damper_push": "damper_push",
    "damper_pull": "damper_pull",
    "arb_rate": "arb_rate",
    "arb_ratio": "arb_ratio",
    "roll_centre": "roll_centre_height",
    "anti_brake": "anti_pitch_brake",
    "anti_drive": "anti_pitch_drive",
    "bump_gap": "bump_gap",
    "rebound_gap": "rebound_gap",
    "stop_rate": "stop_rate",
    "stop_progressive": "stop_progressive_rate",
}


def mounting_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    r"""Sensor-to-body rotation :math:`R_z(\psi) R_y(\theta) R_x(\phi)` of a mounted IMU."""
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))  # fmt: skip
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass(frozen=True, kw_only=True)
class ModelParameters:
    """Parameters of the suspension and equilibrium models (numbers or CasADi symbols).

    Mass and geometry are of the whole vehicle (sprung + unsprung); the aero
    point is relative to the whole-vehicle CG (x forward, z up).
    """

    mass: Any
    lf: Any
    lr: Any
    track_front: Any
    track_rear: Any
    cg_height: Any
    air_density: Any
    reference_area: Any
    lift_coefficient: Any
    drag_coefficient: Any
    aero_x: Any
    aero_z: Any
    spring_front: Any
    spring_rear: Any
    damper_push_front: Any
    damper_pull_front: Any
    damper_push_rear: Any
    damper_pull_rear: Any
    arb_rate_front: Any
    arb_rate_rear: Any
    arb_ratio_front: Any
    arb_ratio_rear: Any
    static_fl: Any
    static_fr: Any
    static_rl: Any
    static_rr: Any
    roll_split_front: Any  # front share of the lateral load transfer (models/roll_split.py)
    # Beyond the paper (wheelload.models.terms): sprung body, tyres, links, stops, IMU.
    sprung_mass: Any
    sprung_cg_height: Any
    inertia_xx: Any
    inertia_yy: Any
    unsprung_front: Any  # kg, one corner
    unsprung_rear: Any
    tyre_rate_front: Any
    tyre_rate_rear: Any
    roll_centre_front: Any
    roll_centre_rear: Any
    anti_brake_front: Any
    anti_brake_rear: Any
    anti_drive_front: Any
    anti_drive_rear: Any
    bump_gap_front: Any
    bump_gap_rear: Any
    rebound_gap_front: Any
    rebound_gap_rear: Any
    stop_rate_front: Any
    stop_rate_rear: Any
    stop_progressive_front: Any
    stop_progressive_rear: Any
    imu_x: Any  # m, IMU relative to the sprung CG
    imu_y: Any
    imu_z: Any
    # Sensor-to-body rotation of the IMU axes, row by row, from [geometry]
    # imu_orientation (R_z(yaw) R_y(pitch) R_x(roll)): a matrix, not angles,
    # so that no step evaluates a trigonometric function for it.
    imu_r11: Any
    imu_r12: Any
    imu_r13: Any
    imu_r21: Any
    imu_r22: Any
    imu_r23: Any
    imu_r31: Any
    imu_r32: Any
    imu_r33: Any
    # Switches, 1.0 on / 0.0 off ([model] section): runtime values in the generated C.
    term_road_frame: Any
    term_body_inertia: Any
    term_geometric_transfer: Any
    term_stops: Any
    term_unsprung_inertia: Any
    term_imu_lever_arm: Any
    # Whole-vehicle CG left of the centreline [m]: 0 for a file's vehicle; a payload
    # estimated online moves it (wheelload.models.payload).
    cg_y: Any = 0.0

    @staticmethod
    def names() -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(ModelParameters))

    @classmethod
    def symbolic(cls, name: str = "p") -> tuple[ca.SX, ModelParameters]:
        """A CasADi SX vector and the parameters unpacked from it."""
        p = ca.SX.sym(name, len(cls.names()))
        return p, cls(**{key: p[i] for i, key in enumerate(cls.names())})

    @classmethod
    def from_vehicle(cls, vehicle: Vehicle, static: np.ndarray | None = None) -> ModelParameters:
        """Numeric parameters; ``static`` overrides the static wheel loads [N].

        The static loads (unless given) and the roll split (unless the file gives
        ``suspension.roll_split_front``) are :func:`derived_function`'s (its compiled C,
        :func:`~wheelload.models.runtime.function_library.compiled_function`).
        """
        terms = dataclasses.asdict(vehicle.model)
        mounting = mounting_matrix(*vehicle.geometry.imu_orientation)
        centre = vehicle_mass_centre(vehicle)
        if static is not None:
            static = np.asarray(static, float)
            if static.shape != (4,) or not np.all(np.isfinite(static)):
                raise ValueError(f"static loads must be 4 finite values, got {static}")
        placeholder = np.zeros(4) if static is None else static  # no derived value reads them
        split = vehicle.suspension.roll_split_front
        front, rear = vehicle.suspension.front, vehicle.suspension.rear
        aero = vehicle.aero
        parameters = cls(
            mass=vehicle.mass.total,
            lf=centre.lf,
            lr=centre.lr,
            track_front=vehicle.geometry.track_front,
            track_rear=vehicle.geometry.track_rear,
            cg_height=centre.height,
            air_density=aero.air_density,
            reference_area=aero.reference_area,
            lift_coefficient=aero.lift_coefficient,
            drag_coefficient=aero.drag_coefficient,
            aero_x=aero.application_point[0] - centre.offset_x,
            aero_z=aero.application_point[2] + vehicle.geometry.cg_height - centre.height,
            static_fl=float(placeholder[0]),
            static_fr=float(placeholder[1]),
            static_rl=float(placeholder[2]),
            static_rr=float(placeholder[3]),
            roll_split_front=0.0 if split is None else split,
            sprung_mass=vehicle.mass.sprung,
            sprung_cg_height=vehicle.geometry.cg_height,
            inertia_xx=vehicle.mass.inertia[0],
            inertia_yy=vehicle.mass.inertia[1],
            unsprung_front=0.5 * vehicle.mass.unsprung_front,
            unsprung_rear=0.5 * vehicle.mass.unsprung_rear,
            tyre_rate_front=vehicle.tyres.vertical_stiffness_front,
            tyre_rate_rear=vehicle.tyres.vertical_stiffness_rear,
            imu_x=vehicle.geometry.imu_position[0],
            imu_y=vehicle.geometry.imu_position[1],
            imu_z=vehicle.geometry.imu_position[2],
            **{
                f"{name}_{axle}": getattr(section, key)
                for axle, section in (("front", front), ("rear", rear))
                for name, key in AXLE_KEYS.items()
            },
            **{f"imu_r{i + 1}{j + 1}": float(mounting[i, j]) for i in range(3) for j in range(3)},
            **{f"term_{key}": float(value) for key, value in terms.items()},
        )
        values = compiled_function(_build_derived_function)(parameters.vector())[0]
        derived = dict(zip(DERIVED, values.ravel()))
        follow = following(vehicle, static_given=static is not None)
        return dataclasses.replace(parameters, **{name: float(derived[name]) for name in follow})

    def imu_rotation(self) -> ca.SX:
        """The sensor-to-body rotation of the IMU as a 3 x 3 matrix."""
        names = [f"imu_r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
        rows = [[getattr(self, names[3 * i + j]) for j in range(3)] for i in range(3)]
        return ca.vertcat(*[ca.horzcat(*row) for row in rows])

    def vector(self) -> np.ndarray:
        """The numeric parameter vector in layout order."""
        return np.array([float(getattr(self, key)) for key in self.names()])

    def static(self) -> tuple[Any, Any, Any, Any]:
        return (self.static_fl, self.static_fr, self.static_rl, self.static_rr)

    def axles(self, *names: str) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
        """The per-axle parameters ``names``: ``((a_front, b_front, ...), (a_rear, ...))``."""
        return tuple(
            tuple(getattr(self, f"{n}_{axle}") for n in names) for axle in ("front", "rear")
        )


#: Parameters derived from other parameters, in :func:`derived_function`'s output order: the
#: static loads (:func:`~wheelload.models.mass_properties.level_static_loads` of ``mass``,
#: ``lf``, ``lr``) and the default roll split
#: (:func:`~wheelload.models.roll_stiffness.roll_split_default`). No derived value reads a
#: derived parameter.
DERIVED = ("static_fl", "static_fr", "static_rl", "static_rr", "roll_split_front")
#: Parameters that enter the whole-vehicle mass centre (``mass``, ``lf``, ``lr``,
#: ``cg_height``, ``aero_x``, ``aero_z``: :func:`~wheelload.models.mass_properties.
#: vehicle_mass_centre`) with vehicle-file values that are not parameters (the sprung CG's
#: axle distances, the tyre radii, the aero application point): a change of one of them
#: alone cannot be carried into the parameters it moves (the generated C refuses it).
MASS_CENTRE_INPUTS = ("sprung_mass", "unsprung_front", "unsprung_rear", "sprung_cg_height")


def following(vehicle: Vehicle, *, static_given: bool = False) -> tuple[str, ...]:
    """The :data:`DERIVED` parameters ``vehicle``'s take from their sources: the static loads
    unless given, the roll split unless the file gives ``suspension.roll_split_front``."""
    given = {"roll_split_front"} if vehicle.suspension.roll_split_front is not None else set()
    given |= {name for name in DERIVED if name.startswith("static_")} if static_given else set()
    return tuple(name for name in DERIVED if name not in given)


def derived_values(p: ModelParameters) -> ca.SX:
    """The :data:`DERIVED` parameters of ``p`` (numbers or symbols) as one SX column."""
    from wheelload.models.roll_stiffness import roll_split_default  # the springs' model

    static = level_static_loads(p.mass, p.lf, p.lr)
    return ca.vertcat(*static, roll_split_default(p))


def derived_function() -> ca.Function:
    """``derived_parameters(p) -> derived[len(DERIVED)]``: :func:`derived_values` (built once
    and stored, :func:`~wheelload.models.runtime.function_cache.stored_function`)."""
    return stored_function(_build_derived_function)


def _build_derived_function() -> ca.Function:
    p_vector, p = ModelParameters.symbolic()
    values = derived_values(p)
    read = {ModelParameters.names()[k] for k in _dependencies(values, p_vector)[1]}
    if read & set(DERIVED):
        raise ValueError(f"a derived parameter reads derived parameters {sorted(read)}")
    return ca.Function("derived_parameters", [p_vector], [values], ["p"], ["derived"])


def derived_sources() -> dict[str, tuple[str, ...]]:
    """Each :data:`DERIVED` parameter's sources: the parameters it depends on (structurally:
    a switch that selects a branch counts, as ``term_geometric_transfer`` for the split)."""
    f = derived_function()
    rows, cols = _dependencies(f.call([f.sx_in(0)])[0], f.sx_in(0))
    names = ModelParameters.names()
    return {
        name: tuple(names[c] for r, c in zip(rows, cols) if r == k)
        for k, name in enumerate(DERIVED)
    }


def _dependencies(values: ca.SX, p_vector: ca.SX) -> tuple[list[int], list[int]]:
    """(output rows, parameter columns) of the structural Jacobian of ``values``."""
    rows, cols = ca.jacobian_sparsity(values, p_vector).get_triplet()
    return list(rows), list(cols)
