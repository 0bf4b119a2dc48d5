r"""The suspension's loads that need only the parameters: springs, dampers, bars and links.

- :func:`travel_loads`: the paper part of the pseudo-measurement (Siegloff &
  Choi eq. 9), :math:`F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i`;
- :func:`link_loads`: the load through the links (roll centre, anti-pitch),
  the quasi-static geometric transfer of :mod:`wheelload.models.suspension.pseudo_measurement`.

``p`` is a :class:`~wheelload.models.parameters.ModelParameters` (numbers or
symbols); this module sits below it, since the parameters' default roll split
(:mod:`wheelload.models.roll_stiffness`) is taken from these loads.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.aero import aero_forces
from wheelload.models.suspension.elements import anti_roll_bar_forces, damper_force


def travel_loads(d, v, p, damper=None) -> ca.SX:
    r"""Paper part of the pseudo-measurement FL, FR, RL, RR from travel ``d`` and rate ``v``.

    .. math:: F_{z,i} = F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i \quad (eq. 9)

    ``damper(v, axle)`` replaces the linear push/pull damper of eq. 5 (axle 0
    front, 1 rear), e.g. a piecewise-linear map.
    """
    axles = p.axles("spring", "damper_push", "damper_pull", "arb_rate", "arb_ratio")
    static = p.static()
    loads = []
    for axle, (spring, push, pull, arb_rate, arb_ratio) in enumerate(axles):
        left, right = 2 * axle, 2 * axle + 1
        arb = anti_roll_bar_forces(d[left], d[right], arb_rate, arb_ratio)
        for side, wheel in enumerate((left, right)):
            force = damper_force(v[wheel], push, pull) if damper is None else damper(v[wheel], axle)
            loads.append(static[wheel] + spring * d[wheel] + force + arb[side])
    return ca.vertcat(*loads)


def link_loads(f_road, vx, p) -> list:
    """Load through the links per corner FL, FR, RL, RR (roll centre, anti-pitch) [N]."""
    wheelbase = p.lf + p.lr
    _, drag = aero_forces(vx, p)
    force_y = p.mass * f_road[1]
    force_x = p.mass * f_road[0] + drag
    braking = force_x < 0
    axles = (
        (p.lr, p.roll_centre_front, p.track_front, p.anti_brake_front, p.anti_drive_front, -1),
        (p.lf, p.roll_centre_rear, p.track_rear, p.anti_brake_rear, p.anti_drive_rear, 1),
    )
    loads = []
    for arm, height, track, anti_brake, anti_drive, sign in axles:
        lateral = force_y * arm / wheelbase * height / track
        share = ca.if_else(braking, anti_brake, anti_drive)
        longitudinal = 0.5 * share * sign * p.cg_height * force_x / wheelbase
        loads += [longitudinal - lateral, longitudinal + lateral]
    return loads
