r"""The fit's linear algebra in bounded memory: regressors a chunk at a time, R factors kept.

The rows of a data set share their weight (:math:`1/\sigma_g`, the AR(1)
inflation), so one pass over the data at the start values keeps, per data
set, the triangular factor :math:`R_g` of the columns
:math:`X = [Z_F\ \ A_F\ \ r_0]` (instruments if any, the scaled regressors of
the candidate parameters F, the start residual) by an incremental QR: the
running :math:`R_g` stacked over the next chunk's rows and triangularised
again (Golub & Van Loan, Matrix Computations, §6.5). Since
:math:`X = Q R`, any column subset S and set weights :math:`w_g` give the
factor of the weighted subset as the QR of :math:`[w_g R_g[:, S]]_g`, and

- least squares: :math:`\min \|A u - b\| = \min \|R_{AA} u - R_{Ab}\|`;
- two-stage least squares: :math:`P_Z A = Q_Z R_{ZA}`, so
  :math:`\min \|P_Z A u - b\| = \min \|R_{ZA} u - R_{Zb}\|` and the
  singular values of :math:`P_Z A` are those of :math:`R_{ZA}`;
- a robust loss: bounded Newton steps, one pass a step (the factor of the
  rows weighted by the loss's curvature and the gradient accumulated);
- the residuals (for the per-set MAD scale and lag-one autocorrelation,
  :mod:`~wheelload.estimators.identification.residual_stats`) in one pass per
  fit of the identifiability loop, one number per row kept (on disk for a long
  log, :mod:`~wheelload.models.runtime.spill`).

Memory: a chunk of regressors and the factors, (4 F + 1)^2 numbers per data
set; the data and the residuals of a long log stay on disk, read a chunk at a
time. Time is linear in the log's length.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from wheelload.estimators.identification.fit_terms import (
    FitLoss,
    Inliers,
    Layout,
    Problem,
    instrument_columns,
    newton,
    robust_terms,
)
from wheelload.estimators.identification.regressors import (
    CHUNK,
    INSTRUMENT_LAGS,
    Rows,
    chunks,
    sampled_rows,
)
from wheelload.models.runtime.spill import SPILL_BYTES, release, row_values

EPS = np.finfo(float).eps


class Triangle:
    """The R factor of rows added a block at a time (incremental QR)."""

    def __init__(self, width: int) -> None:
        self.R = np.zeros((0, width))

    def add(self, X: np.ndarray) -> None:
        if X.shape[0]:
            self.R = np.linalg.qr(np.vstack([self.R, X]), mode="r")


def _factor(blocks: list[np.ndarray], width: int) -> np.ndarray:
    triangle = Triangle(width)
    for block in blocks:
        triangle.add(block)
    return triangle.R


def _bvls(M: np.ndarray, c: np.ndarray, lower, upper) -> np.ndarray:
    return optimize.lsq_linear(M, c, bounds=(lower, upper), method="bvls").x


class ChunkedDesign:
    """The regression rows of all data sets, passed over a chunk at a time."""

    def __init__(
        self,
        problem: Problem,
        candidates: list[int],
        chunk: int = CHUNK,
        spill_bytes: int = SPILL_BYTES,
    ) -> None:
        self.model, self.sets, self.theta = problem.model, problem.sets, problem.theta
        self.scale = scale = problem.scale
        instrumented = problem.instrumented
        sets, theta = self.sets, self.theta
        self.instrumented, self.chunk, self.spill_bytes = instrumented, chunk, spill_bytes
        self.layout = Layout.of(sets)
        if self.layout.size == 0:
            raise ValueError("no data sample with a measured force or reference load")
        self.candidates = np.array(candidates, int)
        self.position = {int(j): i for i, j in enumerate(candidates)}
        self.lags = len(INSTRUMENT_LAGS) if instrumented else 0
        k = len(candidates)
        width = self.lags * k + k + 1
        triangles = [Triangle(width) for _ in sets]
        self.r0 = row_values(self.layout.size, self.spill_bytes)
        self.peak = np.zeros(theta.size)
        self.group_peak = np.zeros((len(sets), theta.size))
        for start, part in self._passes(instrumented):
            g = int(part.group[0])
            r0 = part.y - part.y_hat
            self.r0[start : start + r0.size] = r0
            peak = np.abs(part.J * scale).max(axis=0)
            self.peak = np.maximum(self.peak, peak)
            self.group_peak[g] = np.maximum(self.group_peak[g], peak)
            cols = self.candidates
            block = [part.J[:, cols] * scale[cols], r0[:, None]]
            if instrumented:
                block.insert(0, instrument_columns(part.Z, cols, self.scale, np.ones(r0.size)))
            triangles[g].add(np.hstack(block))
        self.factors = [t.R for t in triangles]

    def _passes(self, instrumented: bool, *arrays: np.ndarray):
        """(first row, chunk of rows) over all data sets; the pages of the per-row values
        (``r0`` and ``arrays``) on disk dropped after each chunk."""
        start = 0
        for part in chunks(self.model, self.sets, self.theta, instrumented, self.chunk):
            if part.y.size:
                yield start, part
                start += part.y.size
                release(self.r0, *arrays)

    def _columns(self, cols, rhs: bool) -> np.ndarray:
        """Columns of the kept factors: instruments of ``cols`` (lag-major), regressors of
        ``cols``, and the start residual when ``rhs``."""
        k = self.candidates.size
        at = [self.position[int(j)] for j in cols]
        index = [lag * k + i for lag in range(self.lags) for i in at]
        index += [self.lags * k + i for i in at]
        if rhs:
            index.append(self.lags * k + k)
        return np.array(index, int)

    def _weighted(self, cols, weight: np.ndarray, rhs: bool) -> np.ndarray:
        """The R factor of the rows weighted by ``weight`` per set, columns ``_columns``."""
        index = self._columns(cols, rhs)
        blocks = [w * R[:, index] for w, R in zip(weight, self.factors)]
        return _factor(blocks, index.size)

    def _split(self, R: np.ndarray, k: int):
        """(instrument block or None, the regressors' block, the right-hand side) of a factor:
        least squares ``R_AA``, ``R_Ab``; instruments ``R_ZZ``, ``R_ZA``, ``R_Zb``."""
        kz = self.lags * k
        if not self.lags:
            return None, R[:k, :k], R[:k, k] if R.shape[1] > k else None
        rhs = R[:kz, kz + k] if R.shape[1] > kz + k else None
        return R[:kz, :kz], R[:kz, kz : kz + k], rhs

    def _projection(self, R_ZZ, M, c=None):
        """``M`` and ``c`` in the coordinates of the instruments' span, the span cut where
        ``numpy.linalg.lstsq`` on all rows would cut it (singular values below
        eps * max(rows, columns) of the largest), so both fits project alike."""
        U, singular, _ = np.linalg.svd(R_ZZ)
        cut = EPS * max(self.layout.size, R_ZZ.shape[1]) * singular[0]
        basis = U[:, singular > cut]
        return basis.T @ M, None if c is None else basis.T @ c

    def _coefficients(self, R_ZZ, M):
        """:math:`R_{ZZ}^{+} R_{ZA}` with the same cut: instruments times it project."""
        rcond = EPS * max(self.layout.size, R_ZZ.shape[1])
        return np.linalg.lstsq(R_ZZ, M, rcond=rcond)[0]

    def solve(self, cols, sigma, lower, upper, loss: FitLoss) -> np.ndarray:
        k = len(cols)
        weight = 1.0 / sigma
        R_ZZ, M, c = self._split(self._weighted(cols, weight, True), k)
        coefficients = None
        if R_ZZ is not None:
            coefficients = self._coefficients(R_ZZ, M)
            M, c = self._projection(R_ZZ, M, c)
        u = _bvls(M, c, lower, upper)
        if loss is FitLoss.LINEAR:
            return u
        u = np.clip(u, lower, upper)
        return self._newton(cols, weight, u, lower, upper, loss, coefficients)

    def _newton(self, cols, weight, u, lower, upper, loss, coefficients) -> np.ndarray:
        r""":func:`~wheelload.estimators.identification.fit_terms.newton`, one pass a step:
        the factor of :math:`\sqrt{h} A` and the gradient accumulated chunk by chunk."""
        k = len(cols)

        def terms(u):
            triangle, gradient, cost = Triangle(k), np.zeros(k), 0.0
            for start, part in self._passes(self.instrumented):
                w = weight[int(part.group[0])]
                A = self._regressors(part, cols, w, coefficients)
                e = A @ u - self.r0[start : start + part.y.size] * w
                rho, psi, h = robust_terms(e, loss)
                cost += rho.sum()
                gradient += A.T @ psi
                triangle.add(A * np.sqrt(h)[:, None])
            return cost, triangle.R, gradient

        return newton(terms, u, lower, upper)

    def _regressors(self, part: Rows, cols, weight: float, coefficients) -> np.ndarray:
        """A chunk's weighted regressors of ``cols``, projected on the instruments' span
        (:math:`Z R_{ZZ}^{+} R_{ZA}`) when there are instruments."""
        if coefficients is None:
            return part.J[:, cols] * self.scale[cols] * weight
        Z = instrument_columns(part.Z, cols, self.scale, np.full(part.y.size, weight))
        return Z @ coefficients

    def residual(self, cols, u) -> np.ndarray:
        r = row_values(self.layout.size, self.spill_bytes)
        step = u * self.scale[cols]
        for start, part in self._passes(False, r):
            rows = slice(start, start + part.y.size)
            r[rows] = self.r0[rows] - part.J[:, cols] @ step
        return r

    def information(self, cols, inflation, inliers: Inliers | None) -> np.ndarray:
        """A triangular factor with the singular values and Gram matrix of the projected
        weighted regressors (rows ``inliers``, default all)."""
        k = len(cols)
        weight = 1.0 / inflation
        R_ZZ, M, _ = self._split(self._weighted(cols, weight, False), k)
        if inliers is None:
            return M if R_ZZ is None else self._projection(R_ZZ, M)[0]
        coefficients = None if R_ZZ is None else self._coefficients(R_ZZ, M)
        triangle = Triangle(k)
        for start, part in self._passes(self.instrumented, inliers.r):
            g = int(part.group[0])
            A = self._regressors(part, cols, weight[g], coefficients)
            triangle.add(A[inliers.of(slice(start, start + part.y.size), g)])
        return triangle.R

    def final(self, value: np.ndarray) -> tuple[Rows, np.ndarray]:
        """Rows at ``value`` for the figures (a time-spread sample of at most
        :data:`~wheelload.estimators.identification.regressors.SAMPLED` per set) and the
        largest scaled regressor per set and parameter (at the start values: the fitted
        parameters' regressors do not depend on the fitted values)."""
        return sampled_rows(self.model, self.sets, value), self.group_peak
