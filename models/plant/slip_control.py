r"""Wheel-slip control (ABS and traction control) at the plant's internal rate.

A per-wheel torque factor :math:`\lambda_i \in [0, 1]` scales the driver's
drive or brake torque request, :math:`T_i = \lambda_i T_{req,i}`; it stands
for the modulated brake pressure (ABS) or engine/brake torque cut (TCS). It
is a state of the closed loop, integrated with the plant at 1 kHz, so the
modulation is continuous with finite dump and build rates (the hydraulic
modulator of a real ABS) instead of a sample-rate switch:

.. math::
    \dot\lambda_i = -k_r\, \lambda_i \max(\hat s_i - s_r, 0)
                    + k_a\, (1 - \lambda_i) \max(s_a - \hat s_i, 0),
    \qquad \hat s_i = |\kappa_i| / \kappa_p

with :math:`\kappa_i` the tyre's transient slip ratio (the relaxation-length
filter of the wheel-speed slip, Pacejka ch. 7) and :math:`\kappa_p` the slip
of the pure-slip force peak. Between :math:`s_a` and :math:`s_r` (both below
the peak, where :math:`dF_x/d\kappa > 0` makes the wheel spin stable) the
factor holds, so a wheel at the limit settles at a steady slip instead of
cycling. The rear axle is select-low: both rear factors see the larger rear
slip, so the rear brakes put no yaw moment on the car. :math:`\lambda` stays
in [0, 1] because each term vanishes at its bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from wheelload.models.conventions import WHEELS
from wheelload.models.plant.dynamics import (
    INPUT_NAMES,
    OUTPUT_NAMES,
    STATE,
    chunk_from_ode,
    plant_functions,
    vehicle_plant,
)
from wheelload.models.plant.road_surface import RoadSurface
from wheelload.models.plant.tyre import peak_input
from wheelload.models.vehicle.description import Vehicle
from wheelload.models.vehicle.plant_section import TyreForces

FACTOR_NAMES = tuple(f"slip_factor_{w}" for w in WHEELS)
# Outputs of the controlled plant: the plant outputs, then the applied inputs.
CONTROLLED_OUTPUT_NAMES = OUTPUT_NAMES + tuple(f"applied_{name}" for name in INPUT_NAMES)


@dataclass(frozen=True, kw_only=True)
class SlipControl:
    slip_release: float = 0.9  # -, s_r: share of the peak slip above which the factor falls
    slip_apply: float = 0.6  # -, s_a: share of the peak slip below which it rises
    release_rate: float = 100.0  # 1/s per unit slip share, k_r (pressure dump)
    apply_rate: float = 10.0  # 1/s per unit slip share, k_a (pressure build)

    def __post_init__(self) -> None:
        if not 0.0 < self.slip_apply < self.slip_release:
            raise ValueError(
                f"need 0 < slip_apply < slip_release, got {self.slip_apply}, {self.slip_release}"
            )
        for key in ("release_rate", "apply_rate"):
            if not getattr(self, key) > 0.0:
                raise ValueError(f"slip control '{key}' must be > 0, got {getattr(self, key)}")


def peak_slip_ratio(tyre: TyreForces) -> float:
    r"""Slip ratio of the pure longitudinal force peak, :math:`X_p / B_x` (load-independent)."""
    b_x = tyre.slip_stiffness_x / (tyre.shape_x * tyre.friction_x)
    return peak_input(tyre.shape_x, tyre.curvature_x) / b_x


def factor_rate(kappa, factor, peak_slip: float, control: SlipControl):
    """:math:`\\dot\\lambda` of the four wheels (module docstring), select-low on the rear."""
    share = ca.fabs(kappa) / peak_slip
    rear = ca.fmax(share[2], share[3])
    seen = ca.vertcat(share[0], share[1], rear, rear)
    release = control.release_rate * factor * ca.fmax(seen - control.slip_release, 0.0)
    apply = control.apply_rate * (1.0 - factor) * ca.fmax(control.slip_apply - seen, 0.0)
    return apply - release


def controlled_ode(
    vehicle: Vehicle, road: RoadSurface, control: SlipControl, payload: bool = False
) -> ca.Function:
    """``controlled_plant_ode([x; lambda], request) -> (d/dt [x; lambda], [y; applied input])``.

    With ``payload`` the request ends with the payload inputs
    (:data:`~wheelload.models.plant.dynamics.PAYLOAD_INPUT_NAMES`), passed on unscaled;
    the applied input is the plant's own nine.
    """
    ode, _ = plant_functions(vehicle, road, payload=payload)
    n_x = ode.size1_in(0)
    state = ca.SX.sym("x", n_x + len(FACTOR_NAMES))
    request = ca.SX.sym("u", ode.size1_in(1))
    x, factor = state[:n_x], state[n_x:]
    applied = request[: len(INPUT_NAMES)] * ca.vertcat(1.0, factor, factor)  # steer, drive, brake
    if payload:
        xdot, y = ode(x, ca.vertcat(applied, request[len(INPUT_NAMES) :]))
    else:
        xdot, y = ode(x, applied)
    kappa = x[STATE["kappa_fl"] : STATE["kappa_fl"] + 4]
    peak = peak_slip_ratio(vehicle_plant(vehicle).tyre)
    rate = factor_rate(kappa, factor, peak, control)
    return ca.Function(
        "controlled_plant_ode",
        [state, request],
        [ca.vertcat(xdot, rate), ca.vertcat(y, applied)],
        ["x", "u"],
        ["xdot", "y"],
    )


def controlled_chunk_function(
    vehicle: Vehicle,
    road: RoadSurface,
    control: SlipControl,
    internal_rate: float,
    steps: int,
    jit: bool = True,
    payload: bool = False,
) -> ca.Function:
    """``controlled_plant_chunk([x; lambda], request) -> ([x; lambda], [y; applied])``.

    ``steps`` RK4 steps at ``internal_rate`` of :func:`controlled_ode` with
    the request held: the slip control acts at every internal step.
    """
    ode = controlled_ode(vehicle, road, control, payload)
    return chunk_from_ode(ode, internal_rate, steps, "controlled_plant_chunk", jit)
