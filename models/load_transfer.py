r"""Algebraic and quasi-static load transfer (Siegloff & Choi §IV-B, methods B and C).

Body attitude relative to the road from the four travels
(:func:`~wheelload.models.body_attitude.attitude_from_travel`, small angles, ISO 8855: pitch > 0
nose down, roll > 0 right side down; wheelbase :math:`l_f + l_r` of the
equilibrium):

.. math::
    \theta = \frac{\bar d_f - \bar d_r}{l_f + l_r}, \quad
    \varphi = \tfrac12 \Big(\frac{d_{FR} - d_{FL}}{T_f} + \frac{d_{RR} - d_{RL}}{T_r}\Big)

Road-frame specific force :math:`f^r = R_y(\theta) R_x(\varphi) f^b`: the body
accelerometer's reading expressed in axes parallel to the road plane.
Because the accelerometer measures specific force (gravity included), its
road-frame components carry the road grade and bank exactly as the gravity
terms of Alatorre et al. do: :math:`f^r_x = a_x + g\sin\theta_{road}`,
:math:`f^r_y = a_y - g\cos\theta_{road}\sin\varphi_{road}`,
:math:`f^r_z = a_z + g\cos\theta_{road}\cos\varphi_{road}`.

Alatorre-style algebraic loads (lateral transfer shared by the axles in
proportion to their static loads, no aerodynamics):

.. math::
    F_{FL,FR} = \frac{m}{2L}(l_r f_z - h f_x) \mp \frac{m h l_r}{L T_f} f_y, \quad
    F_{RL,RR} = \frac{m}{2L}(l_f f_z + h f_x) \mp \frac{m h l_f}{L T_r} f_y

They satisfy the three rows of :math:`A x = b` (eq. 15-16 without aero) for
:math:`f = f^r`. Quasi-static loads: the static loads moved onto
:math:`A x = b` along the suspension's own stiffness,

.. math:: x = x_0 + K A^\top (A K A^\top)^{-1} (b - A x_0), \quad
          K = \partial z / \partial d

(:math:`z` the suspension model of eq. 9): the load transfer of a rigid body
on its springs and anti-roll bars, which fixes the roll-moment split that the
three equilibrium rows leave open.

The paper's method C as its text states it ("a rigid-body quasi-static (QS)
load-transfer baseline anchored to static axle loads", §IV-B): the static loads
plus the rigid-body transfer of the body-axis longitudinal and lateral specific
force, the lateral transfer split by the static axle loads (:math:`\lambda = l_r/L`,
fixed); no vertical acceleration, aerodynamics or suspension stiffness:

.. math::
    F_{FL,FR} = F_{0} - \frac{m h}{2L} f_x \mp \frac{m h l_r}{L T_f} f_y, \quad
    F_{RL,RR} = F_{0} + \frac{m h}{2L} f_x \mp \frac{m h l_f}{L T_r} f_y
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.body_attitude import road_frame
from wheelload.models.equilibrium import equilibrium_matrix, paper_equilibrium_vector
from wheelload.models.parameters import ModelParameters
from wheelload.models.rigid_loads import algebraic_loads
from wheelload.models.suspension.parts import travel_loads


def suspension_stiffness(p: ModelParameters) -> ca.SX:
    """:math:`K = \\partial z / \\partial d` of the suspension model (springs, anti-roll bars)."""
    d = ca.SX.sym("d", 4)
    z = travel_loads(d, ca.SX.zeros(4), p)
    K = ca.jacobian(z, d)
    # z is affine in d, so K does not depend on d: substitute to drop the symbol.
    return ca.substitute(K, d, ca.SX.zeros(4))


def quasi_static_transfer(x0, K, A, b):
    r"""Loads ``x0`` moved onto :math:`A x = b` along the stiffness ``K`` (module docstring).

    .. math:: x = x_0 + K A^\top (A K A^\top)^{-1} (b - A x_0)

    A rigid body on its suspension: the body's heave, pitch and roll move the
    corners by :math:`G q` with :math:`G` spanning the columns of
    :math:`A^\top` up to the sign of the roll column, and the loads by
    :math:`K G q`; :math:`q` is what satisfies the equilibrium.
    """
    KAt = ca.mtimes(K, A.T)
    return x0 + ca.mtimes(KAt, ca.solve(ca.mtimes(A, KAt), b - ca.mtimes(A, x0)))


def quasi_static_loads(acc, vx, p: ModelParameters):
    """Static loads moved onto :math:`A x = b` along the suspension stiffness (module docstring)."""
    A = equilibrium_matrix(p)
    b = paper_equilibrium_vector(acc, vx, p)
    x0 = ca.vertcat(*p.static())
    K = suspension_stiffness(p)
    return quasi_static_transfer(x0, K, A, b)


def algebraic_function(name: str = "algebraic_load") -> ca.Function:
    """``name(acc[3], pitch, roll, p) -> x[4]``: Alatorre-style loads at a body attitude."""
    acc = ca.SX.sym("acc", 3)
    pitch, roll = ca.SX.sym("pitch"), ca.SX.sym("roll")
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(
        name,
        [acc, pitch, roll, p_vector],
        [algebraic_loads(road_frame(acc, roll, pitch), p)],
        ["acc", "pitch", "roll", "p"],
        ["x"],
    )


def quasi_static_function(name: str = "quasi_static_load") -> ca.Function:
    """``name(acc[3], vx, p) -> x[4]``: the quasi-static wheel loads."""
    acc = ca.SX.sym("acc", 3)
    vx = ca.SX.sym("vx")
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(
        name, [acc, vx, p_vector], [quasi_static_loads(acc, vx, p)], ["acc", "vx", "p"], ["x"]
    )


def equilibrium_split(b, p: ModelParameters, front_share=None):
    r"""The wheel loads that meet the equilibrium rows ``b`` with a given lateral split.

    .. math::
        S_f = \frac{b_2 + l_r b_1}{L}, \quad S_r = \frac{l_f b_1 - b_2}{L}, \quad
        F_{FL,FR} = \frac{S_f}{2} \pm \frac{\lambda b_3}{T_f}, \quad
        F_{RL,RR} = \frac{S_r}{2} \pm \frac{(1 - \lambda) b_3}{T_r}

    (rows of :func:`~wheelload.models.equilibrium.equilibrium_matrix`:
    vertical force, pitch and roll moment); the front share :math:`\lambda`
    of the roll moment is ``front_share``, default :math:`l_r / L` as in
    :func:`~wheelload.models.rigid_loads.algebraic_loads`, which this equals for the paper's ``b``
    without aerodynamics.
    """
    L = p.lf + p.lr
    share = p.lr / L if front_share is None else front_share
    front = (b[1] + p.lr * b[0]) / L
    rear = (p.lf * b[0] - b[1]) / L
    roll_front = share * b[2] / p.track_front
    roll_rear = (1 - share) * b[2] / p.track_rear
    return ca.vertcat(
        front / 2 + roll_front, front / 2 - roll_front, rear / 2 + roll_rear, rear / 2 - roll_rear
    )


def static_transfer_loads(acc, p: ModelParameters):
    """The paper's method C: static loads plus the rigid-body transfer of :math:`f_x, f_y`
    with the lateral split fixed at the static axle loads (module docstring)."""
    transfer = algebraic_loads(ca.vertcat(acc[0], acc[1], 0.0), p)  # f_z = 0: transfer only
    return ca.vertcat(*p.static()) + transfer


def static_transfer_function(name: str = "static_transfer_load") -> ca.Function:
    """``name(acc[3], p) -> x[4]``: the paper's method C loads."""
    acc = ca.SX.sym("acc", 3)
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(name, [acc, p_vector], [static_transfer_loads(acc, p)], ["acc", "p"], ["x"])
