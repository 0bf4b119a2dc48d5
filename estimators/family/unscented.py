r"""Unscented-transform kernels on CasADi matrices (Julier & Uhlmann; Wan & van der Merwe 2000).

Symmetric sigma set of :math:`2n + 1` points with scaling
:math:`\lambda = \alpha^2 (n + \kappa) - n`:

.. math::
    \chi_0 = x, \quad \chi_{\pm i} = x \pm \big(\sqrt{(n + \lambda) P}\big)_i, \\
    W^m_0 = \frac{\lambda}{n + \lambda}, \quad
    W^c_0 = W^m_0 + 1 - \alpha^2 + \beta, \quad W_{\pm i} = \frac{1}{2(n + \lambda)}

with the lower Cholesky factor as the matrix square root. For a linear map
the transformed mean and covariance are exact.
"""

from __future__ import annotations

import casadi as ca

ALPHA, BETA, KAPPA = 1.0, 2.0, 0.0


def cholesky_lower(P):
    r"""Lower :math:`L`, :math:`L L^\top = P` (pivots floored at 0: no NaN in generated code)."""
    n = P.shape[0]
    L = [[0] * n for _ in range(n)]
    for j in range(n):
        pivot = P[j, j] - sum((L[j][k] ** 2 for k in range(j)), 0)
        L[j][j] = ca.sqrt(ca.fmax(pivot, 0))
        for i in range(j + 1, n):
            rest = P[i, j] - sum((L[i][k] * L[j][k] for k in range(j)), 0)
            L[i][j] = ca.if_else(L[j][j] > 0, rest / L[j][j], 0)
    return ca.vertcat(*[ca.horzcat(*row) for row in L])


def weights(n: int):
    """Mean and covariance weights of the :math:`2n + 1` sigma points."""
    lam = ALPHA**2 * (n + KAPPA) - n
    outer = 1.0 / (2.0 * (n + lam))
    w_m = [lam / (n + lam)] + [outer] * (2 * n)
    w_c = [w_m[0] + 1.0 - ALPHA**2 + BETA] + [outer] * (2 * n)
    return w_m, w_c, n + lam


def sigma_points(x, P):
    """The :math:`2n + 1` sigma points of mean ``x`` and covariance ``P`` (list of columns)."""
    n = x.shape[0]
    _, _, spread = weights(n)
    S = cholesky_lower(spread * P)
    return [x] + [x + S[:, i] for i in range(n)] + [x - S[:, i] for i in range(n)]


def unscented_transform(points):
    r"""Mean and covariance :math:`\sum W^c (\chi - \bar x)(\chi - \bar x)^\top` of the points."""
    n = (len(points) - 1) // 2
    w_m, w_c, _ = weights(n)
    mean = sum((w * p for w, p in zip(w_m, points)), ca.DM.zeros(points[0].shape[0]))
    covariance = sum(
        (w * ca.mtimes(p - mean, (p - mean).T) for w, p in zip(w_c, points)),
        ca.DM.zeros(points[0].shape[0], points[0].shape[0]),
    )
    return mean, covariance
