r"""Quarter-car model with the tyre load and the load transfer as inputs (ycoo-umvf paper §2).

Bond-graph equations of motion (eq. 2-4), with the suspension deflection
:math:`q_s > 0` in compression (as the travel ``d``) and z up:

.. math::
    \dot p_s &= k_s q_s + b_s \dot q_s - m_s g - \Delta f_z \\
    \dot p_u &= -k_s q_s - b_s \dot q_s - m_u g + f_z \\
    \dot q_s &= p_u / m_u - p_s / m_s

Translated by the static equilibrium (eq. 5): :math:`\tilde q = q_s - m_s g/k_s`,
:math:`\tilde f_z = f_z - (m_s + m_u) g`; the measured sprung-mass acceleration
is :math:`a_s = \dot p_s / m_s` (accelerometer specific force minus g). The
unknown inputs are :math:`e = [\tilde f_z, \Delta f_z]`, the outputs
:math:`y = [a_s, \tilde q, \dot q]` (the third one is the UMVF's extra
measurement, §4).

The state direction :math:`(p_s, p_u) \propto (m_s, m_u)` (both masses moving
together) is unobservable (§4); :func:`reduced_quarter_car_function` removes it
with :math:`z = T x = [\tilde q, \dot q]`, derived from the full model by the
Jacobians, not written a second time.

Unsprung balance (eq. 3 with eq. 4 differentiated) gives the tyre load from
the suspension force and the unsprung acceleration
:math:`a_u = a_s + \ddot q`: :func:`tyre_load_function`, on top of the
suspension pseudo-measurement of :mod:`wheelload.models.suspension.pseudo_measurement` (spring,
asymmetric damper, anti-roll bar and the static load).
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.parameters import ModelParameters
from wheelload.models.suspension.parts import travel_loads

#: Order of the quarter-car parameter vector.
QUARTER_CAR_PARAMETERS = ("sprung_mass", "unsprung_mass", "spring_rate", "damper_rate")


def quarter_car_function(name: str = "quarter_car") -> ca.Function:
    """``name(x[3], e[2], u, qp[4]) -> (xdot[3], y[3])``: eq. 2-5 in translated coordinates.

    ``x = [p_s, p_u, q~]``, ``e = [f~_z, Delta f_z]``, ``qp`` in
    :data:`QUARTER_CAR_PARAMETERS` order, ``y = [a_s, q~, q_dot]``. The known
    input ``u`` is a further suspension force between the masses (pushing
    them apart like the spring): the anti-roll bar and the damper's departure
    from the linear rate, which the paper's model leaves out (§2).
    """
    x = ca.SX.sym("x", 3)
    e = ca.SX.sym("e", 2)
    u = ca.SX.sym("u")
    qp = ca.SX.sym("qp", len(QUARTER_CAR_PARAMETERS))
    ms, mu, ks, bs = qp[0], qp[1], qp[2], qp[3]
    ps, pu, q = x[0], x[1], x[2]
    q_dot = pu / mu - ps / ms
    # Gravity cancels against the static spring force in translated coordinates (eq. 5).
    suspension = ks * q + bs * q_dot + u
    ps_dot = suspension - e[1]
    pu_dot = -suspension + e[0]
    xdot = ca.vertcat(ps_dot, pu_dot, q_dot)
    y = ca.vertcat(ps_dot / ms, q, q_dot)
    return ca.Function(name, [x, e, u, qp], [xdot, y], ["x", "e", "u", "qp"], ["xdot", "y"])


def reduced_quarter_car_function(name: str = "quarter_car_reduced") -> ca.Function:
    r"""``name(qp) -> (A[2x2], H[2x2], C[3x2], G[3x2], B[2], D[3])`` of the observable part (§4).

    With :math:`z = T x`, :math:`T = [[0, 0, 1], [-1/m_s, 1/m_u, 0]]` and the
    unobservable direction :math:`(m_s, m_u, 0)` in the kernel of :math:`T`
    and invariant under the dynamics: :math:`A_r = T A T^+`,
    :math:`H = T B_e`, :math:`C_r = C T^+`, :math:`G = D_e`; the known input
    enters through :math:`B = T B_u` and :math:`D = D_u`.
    """
    full = quarter_car_function()
    x = ca.SX.sym("x", 3)
    e = ca.SX.sym("e", 2)
    u = ca.SX.sym("u")
    qp = ca.SX.sym("qp", len(QUARTER_CAR_PARAMETERS))
    xdot, y = full(x, e, u, qp)
    A, B = ca.jacobian(xdot, x), ca.jacobian(xdot, e)
    C, D = ca.jacobian(y, x), ca.jacobian(y, e)
    B_u, D_u = ca.jacobian(xdot, u), ca.jacobian(y, u)
    ms, mu = qp[0], qp[1]
    T = ca.vertcat(ca.horzcat(0, 0, 1), ca.horzcat(-1 / ms, 1 / mu, 0))
    # Right inverse of T orthogonal to its kernel: T+ = T' (T T')^-1.
    T_plus = ca.mtimes(T.T, ca.inv(ca.mtimes(T, T.T)))
    reduced = [ca.simplify(m) for m in (T @ A @ T_plus, T @ B, C @ T_plus, D, T @ B_u, D_u)]
    return ca.Function(name, [qp], reduced, ["qp"], ["A", "H", "C", "G", "B", "D"])


def tyre_loads(d, v, a_u, unsprung, p: ModelParameters):
    r"""Tyre loads FL, FR, RL, RR from the unsprung balance (eq. 3):
    :math:`F_z = F_{susp}(d, v) + m_u a_u`, :math:`a_u` the unsprung vertical
    acceleration without gravity (the static load of the suspension model
    already holds the unsprung weight)."""
    return unsprung_balance(travel_loads(d, v, p), a_u, unsprung)


def unsprung_balance(suspension, a_u, unsprung):
    r"""Tyre load from the suspension load and the unsprung acceleration (eq. 3):
    :math:`F_z = F_{susp} + m_u a_u` (any suspension model's :math:`F_{susp}`,
    its static part holding the unsprung weight)."""
    return suspension + unsprung * a_u


def tyre_load_function(name: str = "tyre_load") -> ca.Function:
    """``name(d[4], v[4], a_u[4], m_u[4], p) -> fz[4]``: :func:`tyre_loads` as a Function."""
    d, v, a_u, mu = (ca.SX.sym(k, 4) for k in ("d", "v", "a_u", "m_u"))
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(
        name,
        [d, v, a_u, mu, p_vector],
        [tyre_loads(d, v, a_u, mu, p)],
        ["d", "v", "a_u", "m_u", "p"],
        ["fz"],
    )
