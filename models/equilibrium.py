r"""Quasi-static rigid-body equilibrium of the whole vehicle (Siegloff & Choi §III-C).

.. math:: A x = b, \quad x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]^\top

Derived in ISO 8855 body axes about the whole-vehicle CG, with wheel contact
points at :math:`(l_f, \pm T_f/2, -h)` and :math:`(-l_r, \pm T_r/2, -h)`,
accelerometer specific force :math:`(a_x, a_y, a_z)` (gravity included, so
the relations hold on grades and banks without attitude), aerodynamic lift
:math:`L` and drag :math:`D` acting at :math:`(x_a, 0, z_a)`:

.. math::
    \sum F_i &= m a_z - L \\
    l_f (F_{FL} + F_{FR}) - l_r (F_{RL} + F_{RR}) &= -m h a_x - x_a L - (h + z_a) D \\
    \tfrac{T_f}{2} (F_{FL} - F_{FR}) + \tfrac{T_r}{2} (F_{RL} - F_{RR}) &= -m h a_y

A forward acceleration loads the rear axle, a left turn (:math:`a_y > 0`)
loads the right wheels, lift reduces the total. The paper's eq. (16) prints
:math:`+m h a_x` against its matrix (15); its aerodynamic term agrees with
ours once its rearward design-frame x axis is accounted for. Drag is added
here: the tyres, not the air, carry the part of :math:`m a_x` due to drag.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.parameters import ModelParameters


def aero_forces(vx, p: ModelParameters):
    r"""Aerodynamic lift and drag magnitudes (eq. 18): :math:`\tfrac12 \rho V_x^2 A c`."""
    pressure = 0.5 * p.air_density * vx**2 * p.reference_area
    return pressure * p.lift_coefficient, pressure * p.drag_coefficient


def equilibrium_matrix(p: ModelParameters) -> ca.SX:
    """Rows: vertical force, pitch moment, roll moment; columns FL, FR, RL, RR (eq. 15)."""
    half_f, half_r = 0.5 * p.track_front, 0.5 * p.track_rear
    return ca.vertcat(
        ca.horzcat(1, 1, 1, 1),
        ca.horzcat(p.lf, p.lf, -p.lr, -p.lr),
        ca.horzcat(half_f, -half_f, half_r, -half_r),
    )


def equilibrium_vector(acc, vx, p: ModelParameters) -> ca.SX:
    """Right-hand side from specific force ``acc = (ax, ay, az)`` and speed ``vx`` (eq. 16)."""
    ax, ay, az = acc[0], acc[1], acc[2]
    lift, drag = aero_forces(vx, p)
    m, h = p.mass, p.cg_height
    return ca.vertcat(
        m * az - lift,
        -m * h * ax - p.aero_x * lift - (h + p.aero_z) * drag,
        -m * h * ay,
    )


def equilibrium_function(name: str = "equilibrium") -> ca.Function:
    """``name(acc[3], vx, p) -> (A[3x4], b[3])`` as a CasADi Function."""
    acc = ca.SX.sym("acc", 3)
    vx = ca.SX.sym("vx")
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(
        name,
        [acc, vx, p_vector],
        [equilibrium_matrix(p), equilibrium_vector(acc, vx, p)],
        ["acc", "vx", "p"],
        ["A", "b"],
    )
