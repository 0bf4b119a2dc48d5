r"""Static balance of the vehicle at rest for weighing (ycoo-umvf paper §5, eq. 31-35).

At rest the rigid-body equilibrium of :mod:`wheelload.models.equilibrium`
holds with the accelerometer's specific force (gravity only: the grade and
bank appear in :math:`a_x, a_y`). The unknowns are the whole-vehicle mass
:math:`m`, the CG distance to the front axle :math:`l_f` (the rear one is
:math:`L - l_f` with the axle spacing :math:`L` of the vehicle file), the
CG's lateral offset :math:`y_c` (left positive) and its height :math:`h`.
The residual is the equilibrium's with those substituted, the roll row taken
about the offset CG:

.. math::
    r = A(p) F - b(a, 0; p) - [0, 0, y_c \textstyle\sum_i F_i]^\top

(the paper's eq. 35 writes the four loads through eq. 31-34's load-transfer
formula; the equilibrium rows are the same balance without its assumption
of how an axle splits a roll moment, which the anti-roll bars set). One
attitude fixes :math:`m`, :math:`y_c` and one combination of :math:`l_f` and
:math:`h`; a second attitude with another :math:`a_x / a_z` separates them.

The loads are the tyre loads of the suspension model with the unsprung weight
taken along the body's z axis, :math:`F = F_{susp}(d, v) + m_u (a_z - g)`
(:func:`~wheelload.models.family.quarter_car.tyre_loads` with the unsprung at rest).
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.equilibrium import paper_equilibrium_function
from wheelload.models.parameters import ModelParameters

#: Order of the unknowns.
UNKNOWNS = ("mass", "lf", "lateral_offset", "cg_height")


def standstill_residual_function(name: str = "standstill_residual") -> ca.Function:
    """``name(F[4], acc[3], theta[4], p) -> r[3]``; ``theta`` in :data:`UNKNOWNS` order.

    ``p`` supplies the axle spacing (``lf + lr``), the tracks and the rest.
    """
    F = ca.SX.sym("F", 4)
    acc = ca.SX.sym("acc", 3)
    theta = ca.SX.sym("theta", len(UNKNOWNS))
    p_vector, p = ModelParameters.symbolic()
    names = ModelParameters.names()
    spacing = p.lf + p.lr
    replaced = {"mass": theta[0], "lf": theta[1], "lr": spacing - theta[1], "cg_height": theta[3]}
    p_new = ca.vertcat(
        *[replaced[key] if key in replaced else p_vector[i] for i, key in enumerate(names)]
    )
    A, b = paper_equilibrium_function()(acc, 0.0, p_new)
    offset = ca.vertcat(0, 0, theta[2] * ca.sum1(F))
    residual = ca.mtimes(A, F) - b - offset
    return ca.Function(
        name, [F, acc, theta, p_vector], [residual], ["F", "acc", "theta", "p"], ["r"]
    )
