"""Procedural Kalman-filter kernels on CasADi matrices (SX, MX or DM).

Textbook notation (x, P, z, H, R, K, S). The same code builds the symbolic
filter step that is compiled, emitted as C, and evaluated numerically in
tests.

Example
-------
>>> x, P = predict(x, P, Q)
>>> x, P = update(x, P, z, H, R, mask)
"""

from __future__ import annotations

import casadi as ca


def ldl_solve(S, B):
    r"""Solve :math:`S X = B` for symmetric positive definite ``S`` by :math:`S = L D L^\top`.

    Square-root free, so it emits only +, -, *, / in generated code.
    """
    n = S.shape[0]
    L = [[None] * n for _ in range(n)]
    D = [None] * n
    for j in range(n):
        D[j] = S[j, j] - sum((L[j][k] ** 2 * D[k] for k in range(j)), 0)
        for i in range(j + 1, n):
            L[i][j] = (S[i, j] - sum((L[i][k] * L[j][k] * D[k] for k in range(j)), 0)) / D[j]
    Y = []
    for i in range(n):
        Y.append(B[i, :] - sum((L[i][k] * Y[k] for k in range(i)), 0))
    X = [None] * n
    for i in reversed(range(n)):
        X[i] = Y[i] / D[i] - sum((L[k][i] * X[k] for k in range(i + 1, n)), 0)
    return ca.vertcat(*X)


def symmetrise(P):
    r""":math:`(P + P^\top)/2`."""
    return 0.5 * (P + P.T)


def predict(x, P, Q):
    r"""Random-walk prediction (paper eq. 19): :math:`x^- = x`, :math:`P^- = P + Q`."""
    return x, P + Q


def update(x, P, z, H, R, mask=None):
    r"""Joseph-form measurement update, rows with ``mask == 0`` skipped exactly.

    .. math::
        S = M (H P H^\top + R) M + (I - M), \quad K = P H^\top M S^{-1}, \\
        x^+ = x + K M (z - H x), \quad
        P^+ = (I - K H) P (I - K H)^\top + K R K^\top

    with :math:`M = \mathrm{diag}(mask)`. A skipped row has a zero gain
    column, so it changes neither x nor P. Paper eq. (20)-(25).
    """
    m = H.shape[0]
    n = x.shape[0]
    if mask is None:
        mask = ca.DM.ones(m)
    M = ca.diag(mask)
    innovation = z - ca.mtimes(H, x)
    y = ca.vertcat(*[ca.if_else(mask[i], innovation[i], 0) for i in range(m)])
    S = ca.mtimes([M, ca.mtimes([H, P, H.T]) + R, M]) + ca.diag(1 - mask)
    PHt = ca.mtimes([P, H.T, M])
    K = ldl_solve(S, PHt.T).T
    I_KH = ca.DM.eye(n) - ca.mtimes(K, H)
    P_new = ca.mtimes([I_KH, P, I_KH.T]) + ca.mtimes([K, R, K.T])
    return x + ca.mtimes(K, y), symmetrise(P_new)
