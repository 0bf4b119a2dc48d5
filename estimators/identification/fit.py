r"""Least-squares fit of the suspension parameters, with standard errors and identifiability.

The predictions are linear in the free parameters (see
:func:`~wheelload.estimators.identification.regressors.linear_free_set`),
so with regressors :math:`J` and residual :math:`r_0 = y - \hat y(\theta_0)`

.. math:: \min_{lb \le \Delta \le ub} \sum_k \rho\big((J_k \Delta - r_{0,k}) / \sigma_{g(k)}\big)

with :math:`\rho(r) = r^2` (bounded linear least squares, ``lsq_linear``) or
a robust loss (Huber, soft-L1, ``scipy.optimize.least_squares``). Each data
set ``g`` is weighted by its robust residual scale :math:`\sigma_g`
(1.4826 MAD). Standard errors from :math:`s^2 (A^\top A)^{-1}` with
:math:`A_k = J_k / (\sigma_g \sqrt{\kappa_g})`, where
:math:`\kappa_g = (1 + \rho_g)/(1 - \rho_g)` inflates for the lag-one
autocorrelation :math:`\rho_g` of the residuals (an AR(1) effective sample
size); for a robust loss only the inlier rows (:math:`|r| < 3\sigma`) count.

With ``instrumental`` (two-stage least squares, Söderström & Stoica 1989,
ch. 8) the solver runs on :math:`\hat J = P_Z J`, the regressors projected on
the span of instruments :math:`Z` (the model's regressors at the drive logs'
signals averaged over the samples 2-4 steps before and after,
:func:`~wheelload.estimators.identification.regressors.instruments`), whose
noise is independent of the noise in the regressors: sensor noise in a travel
rate otherwise biases a damper slope towards zero by
:math:`\mathrm{var}(v) / (\mathrm{var}(v) + \sigma_v^2)`. Standard errors and
identifiability then use :math:`\hat J`.

Identifiability (from the singular values of :math:`A\,\mathrm{diag}(|\theta_0|)`,
the information about relative changes): a direction whose 1σ relative
precision :math:`1/s_i` is worse than ``precision`` is not determined by the
data; the parameter with the largest share of that direction is held at the
file value and named in a warning. A fitted value whose standard error
exceeds ``warn_precision`` of its size is named in a milder warning.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from wheelload.estimators.identification.data import DataSet
from wheelload.estimators.identification.model import SuspensionFitModel
from wheelload.estimators.identification.regressors import Rows, evaluate, linear_free_set
from wheelload.models import ModelParameters

MAD_SCALE = 1.4826  # MAD to standard deviation of a normal distribution
ROBUST_SCALE = 1.5  # robust-loss threshold in units of the residual scale
INLIER = 3.0  # |r| / sigma below which a row counts for a robust fit's covariance
ZERO_FORCE = 1e-6  # N, largest regressor effect still taken as no excitation


class FitLoss(enum.Enum):
    """Residual loss of the fit."""

    LINEAR = "linear"
    HUBER = "huber"
    SOFT_L1 = "soft-l1"


@dataclass(frozen=True, kw_only=True)
class FitSettings:
    loss: FitLoss = FitLoss.LINEAR
    fixed: frozenset[str] = frozenset()  # held at the file value
    precision: float = 0.25  # largest 1-sigma relative precision of a fitted direction
    warn_precision: float = 0.10  # relative standard error above which a fitted value is flagged
    lower: dict[str, float] = field(default_factory=dict)  # lower bound per parameter
    upper: dict[str, float] = field(default_factory=dict)  # upper bound per parameter
    # Instrumental variables for the drive logs' regressors (noisy travel rates and
    # accelerations bias least squares towards zero): two-stage least squares.
    instrumental: bool = False


@dataclass(frozen=True, kw_only=True, eq=False)
class Identification:
    """Result of :func:`identify` (``free`` indexes ``names``; ``NaN`` errors for held ones)."""

    names: tuple[str, ...]
    initial: np.ndarray
    value: np.ndarray
    std_error: np.ndarray
    free: tuple[int, ...]
    correlation: np.ndarray  # over ``free``
    held: dict[str, str]  # parameter -> reason
    warnings: tuple[str, ...]
    sources: dict[str, tuple[str, ...]]  # parameter -> data sets that excite it
    sets: tuple[DataSet, ...]
    rows: Rows  # at the solution
    scale: np.ndarray  # robust residual scale per data set [N]
    autocorrelation: np.ndarray  # lag-one residual autocorrelation per data set
    loss: FitLoss

    def residual(self) -> np.ndarray:
        return self.rows.y - self.rows.y_hat

    def rmse(self) -> dict[tuple[str, str], float]:
        """Fit RMSE [N] per (data set, wheel)."""
        r = self.residual()
        table = {}
        for g, data in enumerate(self.sets):
            for wheel in data.rows:
                mask = (self.rows.group == g) & (self.rows.wheel == wheel)
                if mask.any():
                    table[(data.label(), wheel)] = float(np.sqrt(np.mean(r[mask] ** 2)))
        return table

    def value_of(self, name: str) -> float:
        return float(self.value[self.names.index(name)])

    def std_error_of(self, name: str) -> float:
        return float(self.std_error[self.names.index(name)])


def _lag_one(r: np.ndarray, rows: Rows, group: int) -> float:
    """Lag-one autocorrelation of one data set's residuals (per wheel, time order)."""
    values = []
    for wheel in np.unique(rows.wheel[rows.group == group]):
        mask = (rows.group == group) & (rows.wheel == wheel)
        series = r[mask][np.argsort(rows.t[mask], kind="stable")]
        series = series - series.mean()
        if series.size > 2 and np.dot(series, series) > 0:
            values.append(np.dot(series[1:], series[:-1]) / np.dot(series, series))
    return float(np.clip(np.mean(values), 0.0, 0.99)) if values else 0.0


def _scales(r: np.ndarray, rows: Rows, count: int) -> tuple[np.ndarray, np.ndarray]:
    sigma = np.ones(count)
    rho = np.zeros(count)
    for g in range(count):
        mask = rows.group == g
        if mask.any():
            spread = MAD_SCALE * np.median(np.abs(r[mask] - np.median(r[mask])))
            sigma[g] = max(spread, 1e-9 * max(1.0, np.abs(rows.y[mask]).max()))
            rho[g] = _lag_one(r, rows, g)
    return sigma, rho


def _solve(A, b, lower, upper, loss: FitLoss) -> np.ndarray:
    """Bounded (robust) least squares of ``A u = b``."""
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
    return result.x


def _projected(A: np.ndarray, Z: np.ndarray | None) -> np.ndarray:
    r"""Regressors projected on the instruments' span, :math:`Z (Z^\top Z)^{-1} Z^\top A`
    (two-stage least squares; ``A`` itself without instruments)."""
    if Z is None:
        return A
    coefficients = np.linalg.lstsq(Z, A, rcond=None)[0]
    return Z @ coefficients


def _instrument_columns(Z: np.ndarray, cols, scale, weight) -> np.ndarray:
    """Instrument regressors of the free columns, all lags side by side, scaled and weighted."""
    block = Z[:, :, cols] * scale[cols] * weight[:, None, None]
    return block.reshape(block.shape[0], -1)


def _inliers(weighted: np.ndarray, loss: FitLoss) -> np.ndarray:
    """Rows that count for the covariance: all (least squares) or |r|/σ below INLIER."""
    return np.ones(weighted.size, bool) if loss is FitLoss.LINEAR else np.abs(weighted) < INLIER


def _variance_factor(r, sigma, group, free: int, loss: FitLoss) -> float:
    """s^2: mean squared scaled residual of the rows that count, per degree of freedom."""
    weighted = r / sigma[group]
    inliers = _inliers(weighted, loss)
    return float(np.sum(weighted[inliers] ** 2) / max(int(inliers.sum()) - free, 1))


def identify(
    model: SuspensionFitModel,
    sets: tuple[DataSet, ...],
    p: ModelParameters,
    settings: FitSettings = FitSettings(),
) -> Identification:
    """Fit the model's parameters to ``sets`` starting from (and holding at) ``p``'s values."""
    if not sets:
        raise ValueError("no identification data: give --rig or --drive files")
    names = model.parameter_names()
    unknown = sorted(set(settings.fixed) - set(names))
    if unknown:
        raise ValueError(
            f"--fix: no model parameter '{unknown[0]}' (parameters: {', '.join(names)})"
        )
    theta0 = model.initial_values(p)
    free, nonlinear = linear_free_set(model, sets, theta0, settings.fixed)
    held = {n: "held (--fix)" for n in settings.fixed}
    for j in nonlinear:
        held[names[j]] = "held: the model is not linear in it together with the fitted ones"
    rows = evaluate(model, sets, theta0, settings.instrumental)
    scale = np.where(np.abs(theta0) > 0, np.abs(theta0), 1.0)
    warnings = []
    excited = np.abs(rows.J * scale).max(axis=0) > ZERO_FORCE
    for j in list(free):
        if not excited[j]:
            free.remove(j)
            held[names[j]] = "held: not excited by the data"
            warnings.append(
                f"'{names[j]}' is not excited by the data (its regressor is zero on every "
                "sample): held at the file value"
            )
    lower_all = np.array([settings.lower[n] if n in settings.lower else -np.inf for n in names])
    upper_all = np.array([settings.upper[n] if n in settings.upper else np.inf for n in names])
    r0 = rows.y - rows.y_hat
    count = len(sets)
    sigma, rho = _scales(r0, rows, count)
    while free:
        cols = np.array(free)
        weight = 1.0 / sigma[rows.group]
        A = rows.J[:, cols] * scale[cols] * weight[:, None]
        Z = None if rows.Z is None else _instrument_columns(rows.Z, cols, scale, weight)
        b = r0 * weight
        lower = (lower_all[cols] - theta0[cols]) / scale[cols]
        upper = (upper_all[cols] - theta0[cols]) / scale[cols]
        u = _solve(_projected(A, Z), b, lower, upper, settings.loss)
        r = r0 - rows.J[:, cols] @ (u * scale[cols])
        sigma, rho = _scales(r, rows, count)
        inflation = (sigma * np.sqrt((1 + rho) / (1 - rho)))[rows.group][:, None]
        instrument = (
            None
            if rows.Z is None
            else _instrument_columns(rows.Z, cols, scale, 1 / inflation[:, 0])
        )
        info = _projected(rows.J[:, cols] * scale[cols] / inflation, instrument)
        _, singular, vt = np.linalg.svd(info, full_matrices=False)
        weakest = int(np.argmin(singular))
        # Judged on the same footing as the reported standard errors (s^2 (A^T A)^-1).
        precision = np.sqrt(_variance_factor(r, sigma, rows.group, cols.size, settings.loss)) / (
            max(singular[weakest], 1e-300)
        )
        if precision <= settings.precision:
            break
        culprit = int(cols[np.argmax(np.abs(vt[weakest]))])
        partners = [
            names[cols[k]]
            for k in np.argsort(-np.abs(vt[weakest]))[1:3]
            if abs(vt[weakest][k]) > 0.3
        ]
        free.remove(culprit)
        held[names[culprit]] = "held: not identifiable from the data"
        warnings.append(
            f"'{names[culprit]}' is not identifiable from these data (relative precision "
            f"±{100 * precision:.0f} % at 1σ"
            + (f", confounded with {', '.join(partners)}" if partners else "")
            + "): held at the file value; add data that excite it"
        )
    value = theta0.copy()
    std = np.full(len(names), np.nan)
    correlation = np.zeros((0, 0))
    if free:
        cols = np.array(free)
        value[cols] = theta0[cols] + u * scale[cols]
        weighted = r / sigma[rows.group]
        inliers = _inliers(weighted, settings.loss)
        s2 = _variance_factor(r, sigma, rows.group, cols.size, settings.loss)
        A = info[inliers]
        cov = s2 * np.linalg.pinv(A.T @ A)
        std[cols] = np.sqrt(np.maximum(np.diag(cov), 0)) * scale[cols]
        d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
        correlation = cov / np.outer(d, d)
    for j in free:
        relative = std[j] / scale[j]
        if relative > settings.warn_precision:
            warnings.append(
                f"'{names[j]}' is only weakly determined by these data (standard error "
                f"{100 * relative:.0f} % of its size)"
            )
    final = evaluate(model, sets, value)
    sources = {}
    for j in free:
        sources[names[j]] = tuple(
            sets[g].label()
            for g in range(count)
            if np.abs(final.J[final.group == g, j] * scale[j]).max(initial=0) > ZERO_FORCE
        )
    return Identification(
        names=names,
        initial=theta0,
        value=value,
        std_error=std,
        free=tuple(free),
        correlation=correlation,
        held=held,
        warnings=tuple(warnings),
        sources=sources,
        sets=sets,
        rows=final,
        scale=sigma,
        autocorrelation=rho,
        loss=settings.loss,
    )
