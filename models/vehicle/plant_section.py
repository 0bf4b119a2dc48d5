"""Plant-only vehicle parameters: the ``[plant]`` section of a vehicle file.

These describe the ground-truth simulator (:mod:`wheelload.models.plant.dynamics`) and
never reach an estimator: body width, wheel spin inertia, the combined-slip
tyre law, the measured damper maps, driveline limits
and the ISO 8608 road-roughness model. Every value carries its physical source
in the vehicle file. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

from wheelload.models.vehicle.section_checks import (
    SectionKeyError,
    require_non_negative,
    require_positive,
    require_share,
)

Pair = tuple[float, float]
Quad = tuple[float, float, float, float]


@dataclass(frozen=True, kw_only=True)
class Body:
    """The plant's body: its width."""

    width: float  # m, body width (cone lanes of ISO 3888-1)

    def _check(self) -> None:
        require_positive(self, "width")


@dataclass(frozen=True, kw_only=True)
class Wheels:
    """The plant's wheels: spin inertia per axle."""

    spin_inertia_front: float  # kg m^2, wheel + tyre + disc + hub about the spin axis
    spin_inertia_rear: float  # kg m^2

    def _check(self) -> None:
        require_positive(self, "spin_inertia_front")
        require_positive(self, "spin_inertia_rear")


@dataclass(frozen=True, kw_only=True)
class TyreForces:
    r"""Magic-formula coefficients (Pacejka 2012, ch. 4, MF without camber).

    Pure slip :math:`F = D \sin(C \arctan(B x - E (B x - \arctan B x)))` with
    :math:`D = \mu F_z`, :math:`\mu = \mu_0 (1 + p_{D2}\,df_z)`,
    :math:`df_z = (F_z - F_{z0}) / F_{z0}`; combined slip by the theoretical
    (normalised) slip vector.
    """

    nominal_load_front: float  # N, F_z0
    nominal_load_rear: float  # N
    friction_x: float  # -, mu_x0 (p_Dx1)
    friction_y: float  # -, mu_y0 (p_Dy1)
    friction_load_sensitivity: float  # -, p_Dx2 = p_Dy2
    shape_x: float  # -, C_x (p_Cx1)
    shape_y: float  # -, C_y (p_Cy1)
    curvature_x: float  # -, E_x (p_Ex1)
    curvature_y: float  # -, E_y (p_Ey1)
    slip_stiffness_x: float  # -, K_xk / F_z (p_Kx1)
    cornering_stiffness_y: float  # -, p_Ky1: K_ya peak over F_z0
    cornering_load_y: float  # -, p_Ky2: load of the peak over F_z0
    relaxation_length_x: float  # m
    relaxation_length_y: float  # m
    rolling_resistance: float  # -, f_r

    def _check(self) -> None:
        for key in (
            "nominal_load_front",
            "nominal_load_rear",
            "friction_x",
            "friction_y",
            "shape_x",
            "shape_y",
            "slip_stiffness_x",
            "cornering_stiffness_y",
            "cornering_load_y",
            "relaxation_length_x",
            "relaxation_length_y",
        ):
            require_positive(self, key)
        require_non_negative(self, "rolling_resistance")
        for key in ("curvature_x", "curvature_y"):
            if not getattr(self, key) < 1.0:
                raise SectionKeyError(key, f"must be < 1, got {getattr(self, key)}")


@dataclass(frozen=True, kw_only=True)
class DamperMap:
    """Force-velocity points of one axle's damper at the wheel, through (0, 0)."""

    velocities: Pair  # m/s, increasing, > 0
    push: Pair  # N, compression force at those velocities
    pull: Pair  # N, rebound force magnitude at those velocities

    def _check(self) -> None:
        if not 0.0 < self.velocities[0] < self.velocities[1]:
            raise SectionKeyError(
                "velocities", f"must be increasing and > 0, got {self.velocities}"
            )
        for key in ("push", "pull"):
            force = getattr(self, key)
            if not 0.0 < force[0] < force[1]:
                raise SectionKeyError(key, f"must be increasing and > 0, got {force}")


@dataclass(frozen=True, kw_only=True)
class Dampers:
    """The plant's damper maps, front and rear."""

    front: DamperMap
    rear: DamperMap

    def _check(self) -> None:
        pass


@dataclass(frozen=True, kw_only=True)
class Driveline:
    """The plant's driveline: power at the wheels, drive and brake shares."""

    max_power: float  # W, at the wheels
    drive_share_front: float  # -, share of drive torque on the front axle
    brake_share_front: float  # -, share of brake torque on the front axle

    def _check(self) -> None:
        require_positive(self, "max_power")
        for key in ("drive_share_front", "brake_share_front"):
            require_share(self, key)


@dataclass(frozen=True, kw_only=True)
class Roughness:
    r"""ISO 8608 displacement PSD :math:`G_d(n) = G_d(n_0) (n / n_0)^{-w}`."""

    reference_frequency: float  # cycles/m, n_0
    waviness: float  # -, w
    class_psd: Quad  # m^3, G_d(n_0) of classes A, B, C, D (geometric means)
    band: Pair  # cycles/m, lowest and highest spatial frequency generated
    enveloping_length: float  # m, tyre contact-patch averaging length

    def _check(self) -> None:
        require_positive(self, "reference_frequency")
        require_positive(self, "waviness")
        require_positive(self, "enveloping_length")
        if min(self.class_psd) <= 0.0:
            raise SectionKeyError("class_psd", "must be > 0 for every class")
        if not 0.0 < self.band[0] < self.band[1]:
            raise SectionKeyError("band", f"must be increasing and > 0, got {self.band}")


@dataclass(frozen=True, kw_only=True)
class Plant:
    """Everything the ground-truth plant needs beyond the estimator parameters."""

    body: Body
    wheels: Wheels
    tyre: TyreForces
    dampers: Dampers
    driveline: Driveline
    roughness: Roughness

    def _check(self) -> None:
        pass
