r"""Quasi-static rigid-body equilibrium of the whole vehicle (Siegloff & Choi §III-C).

.. math:: A x = b, \quad x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]^\top

Derived in ISO 8855 axes about the whole-vehicle CG, with wheel contact
points at :math:`(l_f, \pm T_f/2, -h)` and :math:`(-l_r, \pm T_r/2, -h)`,
specific force :math:`f = (f_x, f_y, f_z)` at the CG (gravity included, so
the relations hold on grades and banks without attitude), aerodynamic lift
:math:`L` and drag :math:`D` acting at :math:`(x_a, 0, z_a)`:

.. math::
    \sum F_i &= m f_z - L \\
    l_f (F_{FL} + F_{FR}) - l_r (F_{RL} + F_{RR}) &= \Delta_x F - m h' f_x - x_a L
        - (h' + z_a) D - g_I I_{yy} \dot q \\
    \tfrac{T_f}{2} (F_{FL} - F_{FR}) + \tfrac{T_r}{2} (F_{RL} - F_{RR}) &= \Delta_y F
        - m h' f_y + g_I I_{xx} \dot p

with :math:`F = m f_z - L` (the first row). With every term off
(:math:`\Delta = 0`, :math:`h' = h`, :math:`f` the IMU's body-axis reading)
these are the paper's eq. (14)-(16): a forward acceleration loads the rear
axle, a left turn (:math:`f_y > 0`) loads the right wheels, lift reduces the
total. The paper's eq. (16) prints :math:`+m h a_x` against its matrix (15);
its aerodynamic term agrees with ours once its rearward design-frame x axis
is accounted for. Drag is added here: the tyres, not the air, carry the part
of :math:`m a_x` due to drag.

Road frame (gate ``road_frame``, see ``wheelload.models.terms``): the tyre
loads act along the road normal, so the rows are written in road axes:
:math:`f` is the CG specific force rotated by the body's roll :math:`\phi`
and pitch :math:`\theta` relative to the road (from the travel sensors), and
the CG, displaced by that rotation, sits at

.. math:: \Delta_x = \tfrac{m_s}{m} h_s \theta, \quad
    \Delta_y = -\tfrac{m_s}{m} (h_s - h_{rc}) \phi, \quad
    h' = h - \tfrac{m_s}{m} e_{CG}

relative to the contact patches (the sprung body pitches about the ground
and rolls about the roll axis, at :math:`h_{rc} = (l_r h_{rc,f} + l_f
h_{rc,r}) / l`; the unsprung masses stay with the wheels). Small-angle
assumptions: :math:`\phi, \theta` from travel differences over the tracks
and wheelbase (first order), the moment arms to first order in the angles,
the lift and drag along road axes; the rotation of :math:`f` itself is
accurate to 1e-7 (Taylor sine and cosine). To first order in :math:`\phi`
the roll row is then the same as in body axes when :math:`h_{rc} = 0` (the rotated :math:`f_y` loses
:math:`g\phi`, the displaced CG gives it back); the vertical row gains the
:math:`f_y \sin\phi` and :math:`f_x \sin\theta` parts the body-axis
:math:`f_z` misses.

Body inertia (gate ``body_inertia``): the sprung body's angular acceleration
about its principal axes; gyroscopic terms :math:`(I_{zz} - I_{yy}) q r` are
left out. Unsprung inertia (hub accelerometers): the vertical row takes
:math:`\sum m_{u,i} (a_{hub,i} - f_{z,body})`, the unsprung masses' own heave
(both along the body's z axis, so that body roll does not leak into it).
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.aero import aero_forces
from wheelload.models.body_attitude import roll_axis_height
from wheelload.models.conventions import WHEELS
from wheelload.models.inputs import INPUTS, ModelInputs
from wheelload.models.parameters import ModelParameters
from wheelload.models.terms import GATES, body_motion, gate, road_motion


def equilibrium_matrix(p: ModelParameters) -> ca.SX:
    r"""Rows: vertical force, pitch moment, roll moment; columns FL, FR, RL, RR (eq. 15).

    The roll arms are taken about a CG :math:`y_c` left of the centreline
    (``cg_y``, 0 in the paper): :math:`\pm T/2 - y_c`.
    """
    half_f, half_r, y = 0.5 * p.track_front, 0.5 * p.track_rear, p.cg_y
    return ca.vertcat(
        ca.horzcat(1, 1, 1, 1),
        ca.horzcat(p.lf, p.lf, -p.lr, -p.lr),
        ca.horzcat(half_f - y, -half_f - y, half_r - y, -half_r - y),
    )


def equilibrium_vector(u, gates, p: ModelParameters) -> ca.SX:
    """Right-hand side from the inputs ``u`` (eq. 16 and the terms above)."""
    inputs = ModelInputs.unpack(u)
    f, _, omega_dot, phi, theta, heave = road_motion(inputs, gates, p)
    f_body = body_motion(inputs, gates, p)[0]  # the hub accelerometers read along body z
    lift, drag = aero_forces(inputs.vx, p)
    m = p.mass
    sprung_share = p.sprung_mass / m
    roll_centre = roll_axis_height(p)
    h = p.cg_height - sprung_share * heave
    shift_x = sprung_share * p.sprung_cg_height * theta
    shift_y = -sprung_share * (p.sprung_cg_height - roll_centre) * phi
    unsprung = (p.unsprung_front, p.unsprung_front, p.unsprung_rear, p.unsprung_rear)
    heave_force = 0
    for wheel, name in enumerate(WHEELS):
        on = gate(gates, f"unsprung_{name}")
        heave_force += on * unsprung[wheel] * (inputs.hub[wheel] - f_body[2])
    total = m * f[2] - lift + heave_force
    inertia = gate(gates, "body_inertia")
    return ca.vertcat(
        total,
        shift_x * total - m * h * f[0] - p.aero_x * lift - (h + p.aero_z) * drag
        - inertia * p.inertia_yy * omega_dot[1],
        shift_y * total - m * h * f[1] + inertia * p.inertia_xx * omega_dot[0],
    )  # fmt: skip


def rows_function(name: str, inputs: dict[str, ca.SX], A: ca.SX, b: ca.SX) -> ca.Function:
    """``name(*inputs) -> (A[3x4], b[3])``: equilibrium rows :math:`A x = b` as a Function."""
    return ca.Function(name, list(inputs.values()), [A, b], list(inputs), ["A", "b"])


def equilibrium_function(name: str = "equilibrium") -> ca.Function:
    """``name(u, gates, p) -> (A[3x4], b[3])`` as a CasADi Function."""
    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    p_vector, p = ModelParameters.symbolic()
    A = equilibrium_matrix(p)
    return rows_function(
        name, {"u": u, "gates": gates, "p": p_vector}, A, equilibrium_vector(u, gates, p)
    )


def paper_equilibrium_vector(acc, vx, p: ModelParameters) -> ca.SX:
    """Right-hand side of the paper's eq. 16 alone: :func:`equilibrium_vector`
    with every term gate off, from the body-axis specific force and the speed."""
    u = ca.vertcat(ca.SX.zeros(INPUTS.index("ax")), acc, vx)
    u = ca.vertcat(u, ca.SX.zeros(len(INPUTS) - u.shape[0]))
    return equilibrium_vector(u, ca.SX.zeros(len(GATES)), p)


def paper_equilibrium_function(name: str = "equilibrium_paper") -> ca.Function:
    """``name(acc[3], vx, p) -> (A[3x4], b[3])``: the paper's equilibrium (eq. 15-16)."""
    acc = ca.SX.sym("acc", 3)
    vx = ca.SX.sym("vx")
    p_vector, p = ModelParameters.symbolic()
    A = equilibrium_matrix(p)
    return rows_function(
        name, {"acc": acc, "vx": vx, "p": p_vector}, A, paper_equilibrium_vector(acc, vx, p)
    )
