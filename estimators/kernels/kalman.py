"""Procedural Kalman-filter kernels on CasADi matrices (SX, MX or DM).

Textbook notation (x, P, z, H, R, K, S). The same code builds the symbolic
filter step that is compiled, emitted as C, and evaluated numerically in
tests.

Example
-------
>>> x, P = predict(x, P, Q)
>>> x, P = update(x, P, z, H, R, mask)
>>> x, P = sequential_update(x, P, z, H, r, mask)  # diagonal R, fewer operations
"""

from __future__ import annotations

import functools

import casadi as ca


def ldl_solve(S, B):
    r"""Solve :math:`S X = B` for symmetric positive definite ``S`` by :math:`S = L D L^\top`.

    Square-root free, so it emits only ``+ - * /`` in generated code.
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


def upper(P):
    r"""``P`` read from its upper triangle only: :math:`P_{ij} = P_{\min(i,j)\max(i,j)}`.

    No arithmetic; a step built on it depends on the upper-triangle entries
    alone, so generated code can keep ``P`` in symmetric storage.
    """
    n = P.shape[0]
    return ca.vertcat(*[ca.horzcat(*[P[min(i, j), max(i, j)] for j in range(n)]) for i in range(n)])


def scalar_update(x, P, z, h, r, valid=1):
    r"""Joseph-form update with one scalar measurement :math:`z = h x + w`, :math:`w \sim N(0, r)`.

    .. math::
        b = P h^\top, \quad S = h b + r, \quad K = b / S, \quad
        x^+ = x + K (z - h x), \\
        P^+ = (I - K h) P (I - K h)^\top + r K K^\top = P + K (S K - b)^\top - b K^\top

    The expanded Joseph form is stationary in :math:`K` (an error in
    :math:`K` enters :math:`P^+` at second order only); it is evaluated on
    the upper triangle and mirrored, so :math:`P^+` is symmetric by
    construction. ``valid == 0`` gives :math:`K = 0` and leaves x and P
    unchanged exactly, provided z is finite (the caller replaces invalid
    inputs first). The mask multiplies the gain rather than selecting it, so
    that CasADi does not cancel :math:`S K - b` to zero, which would turn the
    Joseph form into the short form :math:`P - b K^\top`.
    """
    x, P, _, _, _ = gated_scalar_update(x, P, z, h, r, valid)
    return x, P


def gated_scalar_update(x, P, z, h, r, valid=1, gate=None):
    r""":func:`scalar_update` that also returns the innovation, its variance and the use.

    ``gate(y, S) -> 0 | 1`` (symbolic), if given, multiplies ``valid``: a
    row whose innovation :math:`y = z - h x` is implausible under
    :math:`S = h P h^\top + r` is skipped exactly. Returns ``(x, P, y, S, use)``.
    """
    n = x.shape[0]
    b = ca.mtimes(P, h.T)
    S = ca.mtimes(h, b) + r
    y = z - ca.mtimes(h, x)
    use = valid if gate is None else valid * gate(y, S)
    masked_gain = use / S
    K = [b[j] * masked_gain for j in range(n)]
    t = [S * K[k] - b[k] for k in range(n)]
    entries = {}
    for j in range(n):
        for k in range(j, n):
            entries[j, k] = (P[j, k] - b[j] * K[k]) + K[j] * t[k]  # short dependency chain
    P_new = ca.vertcat(
        *[ca.horzcat(*[entries[min(j, k), max(j, k)] for k in range(n)]) for j in range(n)]
    )
    return x + ca.vertcat(*K) * y, P_new, y, S, use


def sequential_update(x, P, z, H, r, mask=None):
    r"""The update of :func:`update` for diagonal :math:`R = \mathrm{diag}(r)`, one row at a time.

    With uncorrelated measurement noise the joint update equals the
    :func:`scalar_update` of each row in turn (Simon 2006, *Optimal State
    Estimation*, §6.1, sequential Kalman filtering); this
    form needs no matrix inverse and about a third of the operations.
    """
    x, P, _, _, _ = sequential_update_innovations(x, P, z, H, r, mask)
    return x, P


def sequential_update_innovations(x, P, z, H, r, mask=None, gate=None):
    r"""As :func:`sequential_update`, also returning each row's pre-update innovation.

    Row :math:`i` sees the state after rows :math:`0..i-1`: its innovation
    :math:`y_i = z_i - H_i x` and variance :math:`S_i = H_i P H_i^\top + r_i`
    are those of the sequential filter, so :math:`y_i / \sqrt{S_i}` is
    standard normal under the model. ``gate(i, y, S) -> 0 | 1`` (symbolic)
    may veto a row on its innovation; a vetoed row is skipped exactly.
    Returns ``(x, P, y, S, use)`` with ``use = mask * gate`` per row.
    """
    m = H.shape[0]
    if mask is None:
        mask = ca.DM.ones(m)
    ys, Ss, uses = [], [], []
    for i in range(m):
        row_gate = None if gate is None else functools.partial(gate, i)
        x, P, y, S, use = gated_scalar_update(x, P, z[i], H[i, :], r[i], mask[i], row_gate)
        ys.append(y)
        Ss.append(S)
        uses.append(use)
    return x, P, ca.vertcat(*ys), ca.vertcat(*Ss), ca.vertcat(*uses)
