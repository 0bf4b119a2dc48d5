"""The two-stage KF over a fleet of logs in NumPy (batched over filters) and in numba.

Peers of the batched C step for ``wheelload bench fleet``: the same prediction and the
two sequential Joseph-form updates (Siegloff & Choi §III: suspension pseudo-measurement
:math:`z` with :math:`H = I`, then the equilibrium :math:`A x = b`),

.. math:: P^- = P + q\\,\\Delta t\\,I,\\quad K = P^- H^T (H P^- H^T + R)^{-1},\\quad
          x = x + K (y - H x),\\quad P = (I - K H) P^- (I - K H)^T + K R K^T

for ``B`` filters side by side. :math:`z, A, b, R` come from the model Functions
(:func:`~wheelload.studies.bench.numpy_kf.pseudo_measurements`), computed beforehand
and not timed, as for the filterpy peer; the first sample's prediction carries no prior
information, :math:`P^-_0 = (m g)^2 I`, as in the step. They hold no guards, so they
give the filter's numbers on logs where no guard fires and the mass is the file's
(the payload filter off).

Arrays are laid out time first, ``z[k]`` of shape (B, 4), so that each step reads
contiguous rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.types import Signals
from wheelload.studies.bench.numpy_kf import measurement_noises, pseudo_measurements


@dataclass(frozen=True, kw_only=True)
class FleetArrays:
    """The peers' inputs for B logs of T samples, time first."""

    z: np.ndarray  # (T, B, 4) suspension pseudo-measurements [N]
    A: np.ndarray  # (3, 4) equilibrium matrix
    b: np.ndarray  # (T, B, 3) equilibrium right-hand side
    R: np.ndarray  # (T, B, 7) diagonals of R_s, R_c
    dt: np.ndarray  # (T, B) intervals [s]
    x0: np.ndarray  # (4,) initial loads [N]
    q: float  # process noise density
    prior: float  # (m g)^2: the first sample's prediction variance


def fleet_arrays(
    bases: list[Signals],
    windows: list[tuple[int, int, int]],
    p: np.ndarray,
    tunings: list[np.ndarray],
    x0: np.ndarray,
    weight: float,
) -> FleetArrays:
    """:class:`FleetArrays` of windows ``(base, start, stop)`` of equal length of ``bases``.

    ``tunings[j]`` carries the nominal interval window ``j``'s noise is computed with (the
    batched step's :meth:`~wheelload.estimators.TwoStageKF.tuning_for`).
    """
    measured = [pseudo_measurements(base, p) for base in bases]
    A = measured[0][1]
    if any(not np.array_equal(entry[1], A) for entry in measured):
        raise ValueError("the peers take one equilibrium matrix A for the whole fleet")
    noises: dict[tuple[int, float], np.ndarray] = {}
    length = windows[0][2] - windows[0][1]
    T, B = length, len(windows)
    z, b, R, dt = np.empty((T, B, 4)), np.empty((T, B, 3)), np.empty((T, B, 7)), np.empty((T, B))
    for j, (k, start, stop) in enumerate(windows):
        if stop - start != length:
            raise ValueError("the peers take windows of one length")
        interval = float(TUNING.value(tunings[j], "sample_interval"))
        if (k, interval) not in noises:
            full = np.full(len(bases[k]), interval)
            noises[k, interval] = measurement_noises(bases[k], tunings[j], full)
        z[:, j], b[:, j] = measured[k][0][start:stop], measured[k][2][start:stop]
        R[:, j] = noises[k, interval][start:stop]
        dt[:, j] = sample_intervals(bases[k].t[start:stop])
    q = float(TUNING.value(tunings[0], "process_noise_density"))
    return FleetArrays(z=z, A=A, b=b, R=R, dt=dt, x0=x0, q=q, prior=weight**2)


def numpy_fleet(arrays: FleetArrays) -> np.ndarray:
    """Loads (T, B, 4) of B filters stepped side by side, each step one batched NumPy update."""
    z, A, b, R, dt = arrays.z, arrays.A, arrays.b, arrays.R, arrays.dt
    T, B = dt.shape
    I = np.eye(4)
    x = np.repeat(arrays.x0[None, :].astype(float), B, axis=0)
    P = np.zeros((B, 4, 4))
    out = np.empty((T, B, 4))
    AT = A.T
    for k in range(T):
        if k:
            P = P + (arrays.q * dt[k])[:, None, None] * I
        else:
            P = np.broadcast_to(arrays.prior * I, (B, 4, 4)).copy()
        # suspension update, H = I
        R_s = R[k, :, :4]
        S = P.copy()
        S[:, range(4), range(4)] += R_s
        K = np.linalg.solve(S, P).transpose(0, 2, 1)  # P S^-1 (S, P symmetric)
        x = x + np.einsum("bij,bj->bi", K, z[k] - x)
        IKH = I - K
        P = IKH @ P @ IKH.transpose(0, 2, 1) + (K * R_s[:, None, :]) @ K.transpose(0, 2, 1)
        # equilibrium update, H = A
        R_c = R[k, :, 4:]
        PAT = P @ AT
        S = A @ PAT
        S[:, range(3), range(3)] += R_c
        K = np.linalg.solve(S, PAT.transpose(0, 2, 1)).transpose(0, 2, 1)  # P A^T S^-1
        x = x + np.einsum("bij,bj->bi", K, b[k] - x @ AT)
        IKH = I - K @ A
        P = IKH @ P @ IKH.transpose(0, 2, 1) + (K * R_c[:, None, :]) @ K.transpose(0, 2, 1)
        out[k] = x
    return out


def numba_fleet():
    """The numba-jitted loop of the same filter: ``run(arrays) -> loads (T, B, 4)``, or None
    where numba is not installed (the ``bench`` extra)."""
    try:
        import numba
    except ImportError:
        return None
    kernel = _jitted(numba.njit)

    def run(arrays: FleetArrays) -> np.ndarray:
        out = np.empty(arrays.z.shape)
        kernel(arrays.z, arrays.A, arrays.b, arrays.R, arrays.dt, arrays.x0.astype(float),
               arrays.q, arrays.prior, out)  # fmt: skip
        return out

    return run


def _jitted(njit):  # pragma: no cover - compiled by numba
    """The loop over filters and samples, plain scalar loops compiled by ``njit``."""

    @njit
    def solve(S, M, m, X, L):
        """X (m x c) = S^-1 M, S symmetric positive definite (m x m): Cholesky factor L."""
        for j in range(m):
            s = S[j, j]
            for i in range(j):
                s -= L[j, i] * L[j, i]
            L[j, j] = np.sqrt(s)
            for i in range(j + 1, m):
                r = S[i, j]
                for h in range(j):
                    r -= L[i, h] * L[j, h]
                L[i, j] = r / L[j, j]
        for c in range(M.shape[1]):
            for i in range(m):
                r = M[i, c]
                for h in range(i):
                    r -= L[i, h] * X[h, c]
                X[i, c] = r / L[i, i]
            for i in range(m - 1, -1, -1):
                r = X[i, c]
                for h in range(i + 1, m):
                    r -= L[h, i] * X[h, c]
                X[i, c] = r / L[i, i]

    @njit
    def update(x, P, H, y, r, m, work):
        """One Joseph-form update of (x, P): m measurements y = H x + noise, R = diag(r)."""
        S, HP, X, K, IKH, IKHP, L, e = work
        for i in range(m):
            for c in range(4):
                s = 0.0
                for h in range(4):
                    s += H[i, h] * P[h, c]
                HP[i, c] = s
        for i in range(m):
            for j in range(m):
                s = 0.0
                for h in range(4):
                    s += HP[i, h] * H[j, h]
                S[i, j] = s + (r[i] if i == j else 0.0)
        solve(S, HP[:m], m, X, L)  # X = S^-1 H P = K^T
        for i in range(4):
            for j in range(m):
                K[i, j] = X[j, i]
        for i in range(m):
            s = y[i]
            for h in range(4):
                s -= H[i, h] * x[h]
            e[i] = s
        for i in range(4):
            s = x[i]
            for j in range(m):
                s += K[i, j] * e[j]
            x[i] = s
        for i in range(4):
            for j in range(4):
                s = 1.0 if i == j else 0.0
                for h in range(m):
                    s -= K[i, h] * H[h, j]
                IKH[i, j] = s
        for i in range(4):
            for j in range(4):
                s = 0.0
                for h in range(4):
                    s += IKH[i, h] * P[h, j]
                IKHP[i, j] = s
        for i in range(4):
            for j in range(4):
                s = 0.0
                for h in range(4):
                    s += IKHP[i, h] * IKH[j, h]
                for h in range(m):
                    s += K[i, h] * r[h] * K[j, h]
                P[i, j] = s

    @njit
    def loop(z, A, b, R, dt, x0, q, prior, out):
        T, B = dt.shape
        x = np.empty(4)
        P = np.empty((4, 4))
        eye = np.eye(4)
        work = (np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4)),
                np.empty((4, 4)), np.empty((4, 4)), np.empty((4, 4)), np.empty(4))  # fmt: skip
        for f in range(B):
            for i in range(4):
                x[i] = x0[i]
            for k in range(T):
                for i in range(4):
                    for j in range(4):
                        if k == 0:
                            P[i, j] = prior if i == j else 0.0
                        elif i == j:
                            P[i, j] += q * dt[k, f]
                update(x, P, eye, z[k, f], R[k, f, :4], 4, work)
                update(x, P, A, b[k, f], R[k, f, 4:], 3, work)
                for i in range(4):
                    out[k, f, i] = x[i]

    return loop
