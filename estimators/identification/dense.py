r"""The fit's linear algebra on the whole regressor matrix in memory (the reference).

Memory grows with the log (rows x parameters, three times more with
instruments); :mod:`~wheelload.estimators.identification.streamed` gives the
same numbers in bounded memory and is the default.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from wheelload.estimators.identification.fit_terms import (
    ROBUST_SCALE,
    FitLoss,
    Inliers,
    Layout,
    Problem,
    instrument_columns,
    newton,
    robust_terms,
)
from wheelload.estimators.identification.regressors import Rows, evaluate


def solve(A, b, lower, upper, loss: FitLoss) -> np.ndarray:
    """Bounded (robust) least squares of ``A u = b``.

    A robust loss: scipy's trust-region solver, then Newton steps on the
    whole matrix (the trust-region solver stalls with gradients up to 1e-3 of
    the cost's scale, 5e-8 relative off the minimiser, on the plant's logs).
    """
    first = optimize.lsq_linear(A, b, bounds=(lower, upper), method="bvls").x
    if loss is FitLoss.LINEAR:
        return first
    result = optimize.least_squares(
        lambda u: A @ u - b,
        np.clip(first, lower, upper),
        jac=lambda u: A,
        bounds=(lower, upper),
        loss=loss.value.replace("-", "_"),
        f_scale=ROBUST_SCALE,
        x_scale="jac",
        method="trf",
    )

    def terms(u):
        rho, psi, h = robust_terms(A @ u - b, loss)
        return rho.sum(), np.linalg.qr(A * np.sqrt(h)[:, None], mode="r"), A.T @ psi

    return newton(terms, result.x, lower, upper)


def _projected(A: np.ndarray, Z: np.ndarray | None) -> np.ndarray:
    r"""Regressors projected on the instruments' span, :math:`Z (Z^\top Z)^{-1} Z^\top A`
    (two-stage least squares; ``A`` itself without instruments)."""
    if Z is None:
        return A
    coefficients = np.linalg.lstsq(Z, A, rcond=None)[0]
    return Z @ coefficients


class DenseDesign:
    """The regression rows of all data sets at the start values, held in memory."""

    def __init__(self, problem: Problem) -> None:
        self.model, self.sets, self.scale = problem.model, problem.sets, problem.scale
        self.rows = evaluate(self.model, self.sets, problem.theta, problem.instrumented)
        self.layout = Layout.of(self.sets)
        self.r0 = self.rows.y - self.rows.y_hat
        self.peak = np.abs(self.rows.J * self.scale).max(axis=0)

    def solve(self, cols, sigma, lower, upper, loss: FitLoss) -> np.ndarray:
        rows, scale = self.rows, self.scale
        weight = 1.0 / sigma[rows.group]
        A = rows.J[:, cols] * scale[cols] * weight[:, None]
        Z = None if rows.Z is None else instrument_columns(rows.Z, cols, scale, weight)
        return solve(_projected(A, Z), self.r0 * weight, lower, upper, loss)

    def residual(self, cols, u) -> np.ndarray:
        return self.r0 - self.rows.J[:, cols] @ (u * self.scale[cols])

    def information(self, cols, inflation, inliers: Inliers | None) -> np.ndarray:
        """The projected weighted regressors (rows ``inliers``, default all)."""
        rows, scale = self.rows, self.scale
        per_row = inflation[rows.group][:, None]
        instrument = (
            None if rows.Z is None else instrument_columns(rows.Z, cols, scale, 1 / per_row[:, 0])
        )
        info = _projected(rows.J[:, cols] * scale[cols] / per_row, instrument)
        return info if inliers is None else info[inliers.of(slice(None), rows.group)]

    def final(self, value: np.ndarray) -> tuple[Rows, np.ndarray]:
        """The rows at ``value`` and the largest scaled regressor per set and parameter."""
        rows = evaluate(self.model, self.sets, value)
        peak = np.zeros((len(self.sets), rows.J.shape[1]))
        for g in range(len(self.sets)):
            mask = rows.group == g
            if mask.any():
                peak[g] = np.abs(rows.J[mask] * self.scale).max(axis=0)
        return rows, peak
