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


def piecewise_damper_force(v, knots, push_slopes, pull_slopes):
    r"""Piecewise-linear damper map through (0, 0) with slopes between velocity knots.

    .. math:: F(v) = \sum_j c_{push,j}\, \mathrm{clip}(v - v_{j-1}, 0, v_j - v_{j-1})
              \ (v \ge 0), \qquad
              F(v) = -\sum_j c_{pull,j}\, \mathrm{clip}(-v - v_{j-1}, 0, v_j - v_{j-1})
              \ (v < 0)

    with :math:`v_0 = 0` and the last segment unbounded; ``knots`` are the
    inner velocities :math:`v_1 < v_2 < \dots` [m/s] and each slope list has
    ``len(knots) + 1`` entries. Linear in the slopes; one slope per segment
    gives the paper's eq. 5.
    """
    edges = [0.0, *knots]

    def branch(speed, slopes):
        force = 0
        for j, slope in enumerate(slopes):
            past = ca.fmax(speed - edges[j], 0)
            width = edges[j + 1] - edges[j] if j + 1 < len(edges) else None
            force = force + slope * (past if width is None else ca.fmin(past, width))
        return force

    return ca.if_else(v >= 0, branch(v, push_slopes), -branch(-v, pull_slopes))


def anti_roll_bar_forces(d_left, d_right, rate, ratio):
    r"""Anti-roll-bar loads on the left and right wheel (eq. 6-8, sign corrected).

    .. math:: \eta = \gamma (d_L - d_R), \quad F_L = +k_{arb}\eta, \quad F_R = -k_{arb}\eta
    """
    eta = ratio * (d_left - d_right)
    return rate * eta, -rate * eta


def suspension_loads(d, v, p: ModelParameters, damper=None) -> ca.SX:
    """Pseudo-measured wheel loads FL, FR, RL, RR from travel ``d`` and rate ``v`` (eq. 9).

    ``damper(v, axle)`` replaces the linear push/pull damper of eq. 5 (axle 0
    front, 1 rear), e.g. a piecewise-linear map.
    """
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
                static[wheel]
                + spring * d[wheel]
                + (damper_force(v[wheel], push, pull) if damper is None else damper(v[wheel], axle))
                + arb[side]
            )
    return ca.vertcat(*loads)


def suspension_function(name: str = "suspension_load") -> ca.Function:
    """``name(d[4], v[4], p) -> z[4]``: the suspension pseudo-measurement as a CasADi Function."""
    d = ca.SX.sym("d", 4)
    v = ca.SX.sym("v", 4)
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(name, [d, v, p_vector], [suspension_loads(d, v, p)], ["d", "v", "p"], ["z"])


def piecewise_damper_names(knots) -> tuple[str, ...]:
    """Entry names of the piecewise damper's slope vector: ``damper_{push,pull}_{axle}_{j}``."""
    return tuple(
        f"damper_{side}_{axle}_{j}"
        for axle in ("front", "rear")
        for side in ("push", "pull")
        for j in range(len(knots) + 1)
    )


def piecewise_damper_suspension_function(
    knots, name: str = "suspension_load_piecewise_damper"
) -> ca.Function:
    """``name(d[4], v[4], p, damper) -> z[4]``: eq. 9 with the piecewise damper map.

    ``damper`` holds the slopes in :func:`piecewise_damper_names` order; the
    linear push/pull entries of ``p`` are not used.
    """
    knots = tuple(float(k) for k in knots)
    if not knots or any(k <= 0 for k in knots) or list(knots) != sorted(set(knots)):
        raise ValueError(f"damper knots must be increasing and > 0 m/s, got {knots}")
    segments = len(knots) + 1
    d = ca.SX.sym("d", 4)
    v = ca.SX.sym("v", 4)
    slopes = ca.SX.sym("damper", 4 * segments)
    p_vector, p = ModelParameters.symbolic()

    def damper(speed, axle):
        base = 2 * segments * axle
        push = [slopes[base + j] for j in range(segments)]
        pull = [slopes[base + segments + j] for j in range(segments)]
        return piecewise_damper_force(speed, knots, push, pull)

    z = suspension_loads(d, v, p, damper)
    return ca.Function(name, [d, v, p_vector, slopes], [z], ["d", "v", "p", "damper"], ["z"])
