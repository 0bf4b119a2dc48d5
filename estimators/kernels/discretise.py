r"""Discretisation of linear filters with the sample interval as a CasADi symbol.

First-order hold (inputs linear between samples, Franklin, Powell & Workman
§6.3.2): with

.. math:: e^{M} = \begin{bmatrix} \Phi & \Gamma_1 & \Gamma_2 \\ 0 & I & I \\ 0 & 0 & I
          \end{bmatrix}, \quad
          M = \begin{bmatrix} A T & B T & 0 \\ 0 & 0 & I \\ 0 & 0 & 0 \end{bmatrix}

the state after one interval is
:math:`x_{k+1} = \Phi x_k + \Gamma_1 u_k + \Gamma_2 (u_{k+1} - u_k)`. The
matrix exponential is a Taylor series with scaling and squaring, written as
plain SX arithmetic so that the interval can vary from sample to sample in the
compiled loop.
"""

from __future__ import annotations

import casadi as ca

TAYLOR_TERMS = 12
SQUARINGS = 8  # valid for ||A T|| up to ~ 50 (|M / 2^8| < 0.2)


def expm(M, squarings: int = SQUARINGS, terms: int = TAYLOR_TERMS):
    """Matrix exponential of an SX/DM matrix by scaled Taylor series and repeated squaring."""
    n = M.shape[0]
    scaled = M / 2.0**squarings
    result = ca.SX.eye(n) if isinstance(M, ca.SX) else ca.DM.eye(n)
    power = result
    for k in range(1, terms + 1):
        power = ca.mtimes(power, scaled) / k
        result = result + power
    for _ in range(squarings):
        result = ca.mtimes(result, result)
    return result


def first_order_hold(A, B, dt):
    r"""``(Phi, Gamma1, Gamma2)`` of :math:`\dot x = A x + B u` over an interval ``dt``."""
    n, m = A.shape[0], B.shape[1]
    zero_nm = ca.SX.zeros(n, m)
    M = ca.vertcat(
        ca.horzcat(A * dt, B * dt, zero_nm),
        ca.horzcat(ca.SX.zeros(m, n + m), ca.SX.eye(m)),
        ca.SX.zeros(m, n + 2 * m),
    )
    E = expm(M)
    return E[:n, :n], E[:n, n : n + m], E[:n, n + m :]


def trapezoidal(A, B, dt):
    r"""Tustin (trapezoidal) discretisation in the same form as :func:`first_order_hold`.

    :math:`(I - A T/2) x_{k+1} = (I + A T/2) x_k + B T/2 (u_k + u_{k+1})`, i.e.
    :math:`\Phi = (I - AT/2)^{-1}(I + AT/2)`, :math:`\Gamma_1 = 2\Gamma`,
    :math:`\Gamma_2 = \Gamma`, :math:`\Gamma = (I - AT/2)^{-1} B T/2`.
    """
    n = A.shape[0]
    left = ca.SX.eye(n) - A * dt / 2
    Phi = ca.solve(left, ca.SX.eye(n) + A * dt / 2)
    Gamma = ca.solve(left, B * dt / 2)
    return Phi, 2 * Gamma, Gamma
