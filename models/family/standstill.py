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
(:func:`~wheelload.models.family.quarter_car.tyre_loads` with the unsprung at rest),
plus, where the vehicle file's ``geometric_transfer`` term is on, the load the links
carry (:func:`~wheelload.models.suspension.pseudo_measurement.geometric_loads`: on a
slope the tyres hold the car with in-plane forces whose roll-centre and anti-pitch
couples reach the body past the springs). Those depend on the unknown mass and CG, so
they are evaluated at :math:`\theta` inside the residual: on the bundled car, leaving
them out put the CG height 0.09 m (8σ) low.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.equilibrium import paper_equilibrium_function
from wheelload.models.inputs import INPUTS, ModelInputs
from wheelload.models.parameters import ModelParameters
from wheelload.models.suspension.pseudo_measurement import geometric_loads
from wheelload.models.terms import GATES, gate, road_motion

#: Order of the unknowns.
UNKNOWNS = ("mass", "lf", "lateral_offset", "cg_height")


def standstill_residual_function(name: str = "standstill_residual") -> ca.Function:
    """``name(F[4], u, gates, theta[4], p) -> r[3]``; ``theta`` in :data:`UNKNOWNS` order.

    ``F``: the tyre loads from the travels at the file's parameters; ``u``: the mean
    inputs at rest (:data:`~wheelload.models.inputs.INPUTS`, missing ones 0), whose
    specific force enters the equilibrium; ``gates``: the model's term gates
    (:func:`~wheelload.models.terms.gates_function`). ``p`` supplies the axle spacing
    (``lf + lr``), the tracks and the rest.
    """
    F = ca.SX.sym("F", 4)
    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    theta = ca.SX.sym("theta", len(UNKNOWNS))
    p_vector, p = ModelParameters.symbolic()
    names = ModelParameters.names()
    spacing = p.lf + p.lr
    replaced = {"mass": theta[0], "lf": theta[1], "lr": spacing - theta[1], "cg_height": theta[3]}
    p_new = ca.vertcat(
        *[replaced[key] if key in replaced else p_vector[i] for i, key in enumerate(names)]
    )
    weighed = ModelParameters(**{key: p_new[i] for i, key in enumerate(names)})
    inputs = ModelInputs.unpack(u)
    f_road = road_motion(inputs, gates, weighed)[0]
    links = geometric_loads(f_road, inputs.vx, inputs.d, weighed)
    loads = F + gate(gates, "geometric_transfer") * ca.vertcat(*links)
    A, b = paper_equilibrium_function()(inputs.acc, 0.0, p_new)
    offset = ca.vertcat(0, 0, theta[2] * ca.sum1(loads))
    residual = ca.mtimes(A, loads) - b - offset
    return ca.Function(
        name,
        [F, u, gates, theta, p_vector],
        [residual],
        ["F", "u", "gates", "theta", "p"],
        ["r"],
    )
