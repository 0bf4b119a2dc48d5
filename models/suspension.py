"""Suspension pseudo-measurement of the wheel loads (Siegloff & Choi §II-B, eq. 3-9).

.. math:: F_{z,i} = F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i

Signs in ISO 8855 with compression ``d > 0`` and ``v = dd/dt > 0`` in bump:
the spring and the damper push the wheel down harder when compressed, and the
anti-roll bar adds load to the more compressed wheel of an axle. (The paper's
eq. 6 prints the opposite sign; a stabiliser bar twisted by a left-side bump
pushes the left wheel down and lifts the right, so ``F_L = +k_arb eta``.)

Example
-------
>>> f = suspension_function()
>>> z = f([0.01, 0, 0, 0], [0, 0, 0, 0], ModelParameters.from_vehicle(vehicle).vector())
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.parameters import ModelParameters


def damper_force(v, c_push, c_pull):
    r"""Asymmetric piecewise-linear damper (eq. 5): :math:`c_{push} v` for
    :math:`v \ge 0`, :math:`c_{pull} v` otherwise."""
    return ca.if_else(v >= 0, c_push * v, c_pull * v)


def anti_roll_bar_forces(d_left, d_right, rate, ratio):
    r"""Anti-roll-bar loads on the left and right wheel (eq. 6-8, sign corrected).

    .. math:: \eta = \gamma (d_L - d_R), \quad F_L = +k_{arb}\eta, \quad F_R = -k_{arb}\eta
    """
    eta = ratio * (d_left - d_right)
    return rate * eta, -rate * eta


def suspension_loads(d, v, p: ModelParameters) -> ca.SX:
    """Pseudo-measured wheel loads FL, FR, RL, RR from travel ``d`` and rate ``v`` (eq. 9)."""
    axles = (
        (
            p.spring_front,
            p.damper_push_front,
            p.damper_pull_front,
            p.arb_rate_front,
            p.arb_ratio_front,
        ),
        (p.spring_rear, p.damper_push_rear, p.damper_pull_rear, p.arb_rate_rear, p.arb_ratio_rear),
    )
    static = p.static()
    loads = []
    for axle, (spring, push, pull, arb_rate, arb_ratio) in enumerate(axles):
        left, right = 2 * axle, 2 * axle + 1
        arb = anti_roll_bar_forces(d[left], d[right], arb_rate, arb_ratio)
        for side, wheel in enumerate((left, right)):
            loads.append(
                static[wheel] + spring * d[wheel] + damper_force(v[wheel], push, pull) + arb[side]
            )
    return ca.vertcat(*loads)


def suspension_function(name: str = "suspension_load") -> ca.Function:
    """``name(d[4], v[4], p) -> z[4]``: the suspension pseudo-measurement as a CasADi Function."""
    d = ca.SX.sym("d", 4)
    v = ca.SX.sym("v", 4)
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(name, [d, v, p_vector], [suspension_loads(d, v, p)], ["d", "v", "p"], ["z"])
