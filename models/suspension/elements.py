"""Force laws of the suspension elements at the wheel (Siegloff & Choi eq. 5-8; stops).

Shared by the pseudo-measurement (:mod:`wheelload.models.suspension.pseudo_measurement`), the
road-frame attitude (:mod:`wheelload.models.terms`) and the plant.
"""

from __future__ import annotations

import casadi as ca


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


def stop_force(d, bump_gap, rebound_gap, linear_rate, progressive_rate):
    r"""Bump (> 0) and rebound (< 0) stop force: :math:`k_1 x + k_2 x^2` past each gap.

    .. math:: F = k_1 x_b + k_2 x_b^2 - (k_1 x_r + k_2 x_r^2), \quad
        x_b = \max(d - g_b, 0), \quad x_r = \max(-d - g_r, 0)
    """
    bump = ca.fmax(d - bump_gap, 0.0)
    rebound = ca.fmax(-d - rebound_gap, 0.0)
    return (linear_rate * bump + progressive_rate * bump**2) - (
        linear_rate * rebound + progressive_rate * rebound**2
    )
