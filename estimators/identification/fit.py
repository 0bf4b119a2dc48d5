r"""Least-squares fit of the suspension parameters, with standard errors and identifiability.

The predictions are linear in the free parameters (see
:func:`~wheelload.estimators.identification.regressors.linear_free_set`),
so with regressors :math:`J` and residual :math:`r_0 = y - \hat y(\theta_0)`

.. math:: \min_{lb \le \Delta \le ub} \sum_k \rho\big((J_k \Delta - r_{0,k}) / \sigma_{g(k)}\big)

with :math:`\rho(r) = r^2` (bounded linear least squares, BVLS) or a robust
loss (Huber, soft-L1: bounded Newton steps to the minimiser). Each data
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

The linear algebra runs by default over chunks of samples with triangular
factors kept (:mod:`~wheelload.estimators.identification.streamed`: memory
bounded by the parameter count and one chunk; a long log's data and residuals
stay on disk, :mod:`~wheelload.models.runtime.spill`);
``FitPath.DENSE`` holds the whole regressor matrix
(:mod:`~wheelload.estimators.identification.dense`, the reference: the two
agree to 1e-9 relative).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from wheelload.estimators.identification import residual_stats
from wheelload.estimators.identification.data import DataSet
from wheelload.estimators.identification.dense import DenseDesign
from wheelload.estimators.identification.fit_terms import FitLoss, Inliers, Problem
from wheelload.estimators.identification.model import SuspensionFitModel
from wheelload.estimators.identification.regressors import CHUNK, Rows, linear_free_set
from wheelload.estimators.identification.streamed import ChunkedDesign
from wheelload.models import ModelParameters
from wheelload.models.runtime.spill import SPILL_BYTES

ZERO_FORCE = 1e-6  # N, largest regressor effect still taken as no excitation

__all__ = ["FitLoss", "FitPath", "FitSettings", "Identification", "identify"]


class FitPath(enum.Enum):
    """How the regressors are held: a chunk at a time with R factors kept (bounded memory,
    :mod:`~wheelload.estimators.identification.streamed`) or all in memory (the reference,
    :mod:`~wheelload.estimators.identification.dense`)."""

    CHUNKED = "chunked"
    DENSE = "dense"


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
    path: FitPath = FitPath.CHUNKED
    chunk: int = CHUNK  # samples per chunk of the chunked path
    spill_bytes: int = SPILL_BYTES  # per-row values of the chunked path beyond this: on disk


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
    rows: Rows  # at the solution (chunked path: a time-spread sample of each set's rows)
    scale: np.ndarray  # robust residual scale per data set [N]
    autocorrelation: np.ndarray  # lag-one residual autocorrelation per data set
    loss: FitLoss
    fit_rmse: dict[tuple[str, str], float]  # (data set, wheel) -> RMSE [N], all rows

    def residual(self) -> np.ndarray:
        return self.rows.y - self.rows.y_hat

    def rmse(self) -> dict[tuple[str, str], float]:
        """Fit RMSE [N] per (data set, wheel)."""
        return dict(self.fit_rmse)

    def value_of(self, name: str) -> float:
        return float(self.value[self.names.index(name)])

    def std_error_of(self, name: str) -> float:
        return float(self.std_error[self.names.index(name)])


def _design(model, sets, theta0, scale, free, settings: FitSettings):
    problem = Problem(
        model=model, sets=sets, theta=theta0, scale=scale, instrumented=settings.instrumental
    )
    if settings.path is FitPath.DENSE:
        return DenseDesign(problem)
    return ChunkedDesign(problem, free, chunk=settings.chunk, spill_bytes=settings.spill_bytes)


def identify(
    model: SuspensionFitModel,
    sets: tuple[DataSet, ...],
    p: ModelParameters,
    settings: FitSettings = FitSettings(),
) -> Identification:
    """Fit the model's parameters to ``sets`` starting from (and holding at) ``p``'s values.

    The fit's matrices are narrow (a column per candidate parameter and instrument): LAPACK's
    QR of them is level-2 work that BLAS threads do not speed up, and on a loaded machine
    their waiting for each other made a chunk's QR 17 times slower (6.5 against 109 ms for
    16 406 x 22). The fit runs with one BLAS thread.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _identify(model, sets, p, settings)


def _identify(
    model: SuspensionFitModel,
    sets: tuple[DataSet, ...],
    p: ModelParameters,
    settings: FitSettings,
) -> Identification:
    if not sets:
        raise ValueError("no identification data: give --rig or --drive files")
    if settings.chunk < 1:
        raise ValueError(f"chunk: give a positive number of samples, not {settings.chunk}")
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
    scale = np.where(np.abs(theta0) > 0, np.abs(theta0), 1.0)
    design = _design(model, sets, theta0, scale, free, settings)
    layout = design.layout
    warnings = []
    excited = design.peak > ZERO_FORCE
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
    r = design.r0
    sigma, rho = residual_stats.scales(r, layout)
    while free:
        cols = np.array(free)
        lower = (lower_all[cols] - theta0[cols]) / scale[cols]
        upper = (upper_all[cols] - theta0[cols]) / scale[cols]
        u = design.solve(cols, sigma, lower, upper, settings.loss)
        r = design.residual(cols, u)
        sigma, rho = residual_stats.scales(r, layout)
        inflation = sigma * np.sqrt((1 + rho) / (1 - rho))
        info = design.information(cols, inflation, None)
        _, singular, vt = np.linalg.svd(info, full_matrices=False)
        weakest = int(np.argmin(singular))
        # Judged on the same footing as the reported standard errors (s^2 (A^T A)^-1).
        s2 = residual_stats.variance_factor(r, sigma, layout, cols.size, settings.loss)
        precision = np.sqrt(s2) / (max(singular[weakest], 1e-300))
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
        s2 = residual_stats.variance_factor(r, sigma, layout, cols.size, settings.loss)
        if settings.loss is not FitLoss.LINEAR:
            info = design.information(cols, inflation, Inliers(r, sigma, settings.loss))
        A = info
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
    rows, peak = design.final(value)
    sources = {
        names[j]: tuple(sets[g].label() for g in range(len(sets)) if peak[g, j] > ZERO_FORCE)
        for j in free
    }
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
        rows=rows,
        scale=sigma,
        autocorrelation=rho,
        loss=settings.loss,
        fit_rmse=residual_stats.rmse(r, layout),
    )
