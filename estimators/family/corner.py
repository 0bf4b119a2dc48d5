r"""Corner-based vertical load estimator (corner-based paper §III-C, eq. 17-18).

Loads from the body IMU alone (the paper's method uses no travel sensor):
the specific force rotated by the body roll and pitch relative to the road,
the rigid-body axle loads (eq. 17) and their left/right split with the
roll-centre term (eq. 18), written once in :mod:`wheelload.models.family.corner_loads`.

The roll and pitch angles come from a drift-compensated rate observer (after
Rehm, the paper's ref. [18]):

.. math:: \dot{\hat\phi} = \omega_x + L_\phi(\phi_{st} - \hat\phi), \quad
          \dot{\hat\theta} = \omega_y + L_\theta(\theta_{st} - \hat\theta)

with the stationary angles of the suspension's roll and pitch stiffness
(:func:`~wheelload.models.body_attitude.roll_pitch_stiffness`),
:math:`\phi_{st} = m_s (h_s - h_{rc}) a_y / K_\phi` and
:math:`\theta_{st} = -m_s (h_s - h_{rc}) a_x / K_\theta` (a left turn rolls
the body to the right, braking dips the nose), integrated exactly over each
interval with the rate held. Without gyro rates the observer reduces to a
first-order lag on the stationary angles. A constant gyro bias :math:`b`
leaves an angle error :math:`b / L` instead of a growing one.

Settings: ``roll_centre_height`` (default: with the full model, the
vehicle file's roll centres weighted by the axle loads,
:math:`(l_r h_{rc,f} + l_f h_{rc,r}) / L`, as in the KF's equilibrium; with
the paper model 0 m, the ground) and the observer gain (default 1 /s). The
equilibrium residual is reported against the chosen model's equilibrium
(:mod:`~wheelload.estimators.family.suspension_model`); the loads are the
paper's eq. 17-18 either way (the method uses no suspension
pseudo-measurement). The step is a CasADi Function; ``run`` loops it in
compiled C. No standard deviation.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import step_flags, step_name
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import equilibrium_residual
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models import INPUTS, ModelParameters, Vehicle, vehicle_mass_centre
from wheelload.models.body_attitude import roll_axis_height, roll_pitch_stiffness
from wheelload.models.family.corner_loads import corner_load_function
from wheelload.models.input_validity import interval_is_valid, sanitise


@dataclass(frozen=True, kw_only=True)
class CornerSettings:
    """Roll-centre height above ground [m] and the rate observer's gain [1/s]."""

    roll_centre_height: float | None = None  # None: from the vehicle file (full model) or 0
    observer_gain: float = 1.0

    def __post_init__(self) -> None:
        height = 0.0 if self.roll_centre_height is None else self.roll_centre_height
        if not height >= 0 or not self.observer_gain > 0:
            raise ValueError(
                "corner settings: roll_centre_height must be >= 0 and observer_gain > 0, got "
                f"{self.roll_centre_height}, {self.observer_gain}"
            )


def roll_centre_height(vehicle: Vehicle, settings: CornerSettings, model: SuspensionModel) -> float:
    """The settings' roll-centre height, else the vehicle file's (full model) or 0 (paper)."""
    if settings.roll_centre_height is not None:
        return settings.roll_centre_height
    if model is SuspensionModel.PAPER:
        return 0.0
    return float(roll_axis_height(ModelParameters.from_vehicle(vehicle)))


def corner_parameters(
    vehicle: Vehicle, settings: CornerSettings, model: SuspensionModel = DEFAULT_MODEL
) -> np.ndarray:
    """Whole-vehicle mass, CG to axles, CG height, tracks, roll-centre height."""
    centre = vehicle_mass_centre(vehicle)
    g = vehicle.geometry
    return np.array(
        [vehicle.mass.total, centre.lf, centre.lr, centre.height, g.track_front, g.track_rear,
         roll_centre_height(vehicle, settings, model)]
    )  # fmt: skip


def step_function(
    vehicle: Vehicle, settings: CornerSettings, model: SuspensionModel = DEFAULT_MODEL
) -> ca.Function:
    """The step: angles and held loads carried; outputs loads, std, residual, flags."""
    angles = ca.SX.sym("angles", 2)
    held = ca.SX.sym("loads_held", 4)
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    cp = ca.SX.sym("cp", 7)
    p = ca.SX.sym("p", len(ModelParameters.names()))
    u = sanitise(u_raw, valid)
    acc, rates = u[8:11], u[12:15]
    k = roll_pitch_stiffness(vehicle)
    arm = vehicle.geometry.cg_height - cp[6]
    lever = vehicle.mass.sprung * arm
    stationary = ca.vertcat(lever * acc[1] / k.roll, -lever * acc[0] / k.pitch)
    acc_ok = valid[8] * valid[9] * valid[10]
    ok = interval_is_valid(dt)
    dt_safe = ca.if_else(ok, dt, 1e-3)
    gain = settings.observer_gain
    decay = ca.exp(-gain * dt_safe)
    rate = ca.vertcat(rates[0] * valid[12], rates[1] * valid[13])
    # Exact solution over the interval with rate and stationary angle held.
    with_acc = stationary + decay * (angles - stationary) + rate * (1 - decay) / gain
    only_rates = angles + rate * dt_safe
    new_angles = ca.if_else(ok, ca.if_else(acc_ok, with_acc, only_rates), angles)
    loads = corner_load_function()(acc, new_angles[0], new_angles[1], cp)
    loads = ca.if_else(ca.logic_and(ok, acc_ok), loads, held)
    residual, _ = equilibrium_residual(model, u, valid, p, loads)
    rejected = 1 - ok
    missing = ca.fmax(1 - acc_ok, rejected)
    flags = step_flags([rejected] * 4, missing, rejected)
    return ca.Function(
        step_name("wheelload_corner_step", model),
        [angles, held, u_raw, valid, dt, cp, p],
        [new_angles, loads, loads, ca.DM.zeros(4), residual, flags],
        ["angles", "loads_held", "u", "u_valid", "dt", "cp", "p"],
        ["angles_next", "loads_next", "loads", "std", "residual", "flags"],
    )


class CornerBased(FamilyMethod):
    """Eq. 17-18 with a drift-compensated roll / pitch rate observer; compiled loop."""

    name = "corner-based"
    has_std = False

    def __init__(
        self,
        vehicle: Vehicle,
        settings: CornerSettings = CornerSettings(),
        *,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        self.settings = settings
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return step_function(self.vehicle, self.settings, self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        """The angles (zero) and the loads held for a rejected sample (static)."""
        return (np.zeros(2), *super().initial_arrays())

    def fixed_arrays(self) -> tuple[np.ndarray, ...]:
        """The corner parameters (eq. 17-18) and the model parameters."""
        corner = corner_parameters(self.vehicle, self.settings, self.suspension)
        return (corner, self.parameters.vector())


@dataclass(frozen=True, kw_only=True)
class CornerOptions:
    """Options of the corner-based method (``build("corner", vehicle, **options)``)."""

    settings: CornerSettings = CornerSettings()  # roll-centre height, observer gain


INFO = MethodInfo(
    name="corner",
    description="corner loads from IMU roll/pitch (drift-compensated rate observer), roll centre",
    reference="corner-based paper §III-C, eq. 17-18; roll/pitch observer after Rehm",
    build=CornerBased,
    options=CornerOptions,
    model_choice=True,
)
