r"""Default front share of the lateral load transfer (:mod:`wheelload.models.roll_split`).

.. math:: \lambda_K = \frac{K_f}{K_f + K_r}, \quad K = \tfrac{T}{2}\,
          \frac{\partial (F_L - F_R)}{\partial\varphi}, \qquad
          \lambda = \frac{M_{g,f} + \lambda_K (m f_y h - M_{g,f} - M_{g,r})}{m f_y h}

the roll-stiffness share of the suspension model's own Jacobian (springs and
anti-roll bars), with the link moments :math:`M_{g,a}` when the
``geometric_transfer`` term is on. ``p`` is a
:class:`~wheelload.models.parameters.ModelParameters` of numbers or CasADi symbols;
the result is an SX expression in ``p`` (a constant for numbers). The parameters take
their default split from here, through their derived-parameter Function
(:func:`wheelload.models.parameters.derived_function`), which the generated C also
evaluates when a spring or bar is set at run time.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.suspension.parts import link_loads, travel_loads


def roll_stiffness_share_front(p) -> ca.SX:
    """Front share of the roll stiffness of the suspension model (springs and bars)."""
    d = ca.SX.sym("d", 4)
    jacobian = ca.jacobian(travel_loads(d, ca.DM.zeros(4), p), d)
    J = ca.substitute(jacobian, d, ca.DM.zeros(4))  # at the static position
    stiffness = []
    for (left, right), track in (((0, 1), p.track_front), ((2, 3), p.track_rear)):
        roll = [ca.SX(0.0)] * 4
        roll[left], roll[right] = 0.5 * track, -0.5 * track  # travel per radian of roll
        loads = ca.mtimes(J, ca.vertcat(*roll))
        stiffness.append(0.5 * track * (loads[left] - loads[right]))
    return stiffness[0] / (stiffness[0] + stiffness[1])


def roll_split_default(p) -> ca.SX:
    """Default front share of the lateral load transfer (:mod:`wheelload.models.roll_split`).

    The roll-stiffness share, with the link (roll-centre) moments of
    :func:`~wheelload.models.suspension.parts.link_loads` added when the
    ``geometric_transfer`` switch of ``p`` is on.
    """
    elastic = roll_stiffness_share_front(p)
    lateral = 1.0  # m/s^2; the split does not depend on it (every part is linear in f_y)
    links = link_loads(ca.DM([0.0, lateral, 0.0]), 0.0, p)
    # A left turn (f_y > 0) loads the right wheels: moments as right minus left.
    moment_front = 0.5 * p.track_front * (links[1] - links[0])
    moment_rear = 0.5 * p.track_rear * (links[3] - links[2])
    total = p.mass * lateral * p.cg_height
    linked = (moment_front + elastic * (total - moment_front - moment_rear)) / total
    return ca.if_else(p.term_geometric_transfer > 0.5, linked, elastic)
