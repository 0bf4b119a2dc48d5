r"""Tuning of the two-stage KF's noise densities: innovation likelihood and reference RMSE.

Prediction-error method (Mehra 1970; Ljung, *System Identification*, §7):
the filter's sequential innovations :math:`y_{k,i}` with variances
:math:`S_{k,i}` (outputs of the filter step itself) are independent normals
under the model, so the tuning :math:`\theta = \log(q, r_s, r_{c,1..3})`
maximises

.. math:: \ell(\theta) = -\tfrac12 \sum_{k,i} \big(\log 2\pi S_{k,i} + y_{k,i}^2 / S_{k,i}\big)

over every row whose inputs are present (Nelder-Mead in the log-parameters, each within a
factor 1000 of the input: the pseudo-measurement error is correlated in
time, and unbounded the white-noise likelihood may drive ``r_s`` to zero).
The likelihood is evaluated with the innovation gate open: a gate removes
exactly the large innovations the likelihood needs, and a shrinking
tuning would gate more and more of them away. Everything else (the
estimates, the coverage, the RMSE) runs with the guard settings the filter
of the written file runs with (:class:`~wheelload.estimators.TwoStageKF`'s
own). With reference loads, the tuning that minimises the pooled RMSE is
found the same way, and the tuning written is the likelihood shape or the
input's shape (whichever has the lower pooled RMSE with the guards), scaled
as a whole by c so that ±2σ covers 95 % of the error: the model errors are
correlated in time, which the white-noise likelihood cannot see. Scaling
leaves the gain unchanged and scales P and every innovation variance S by
c; the innovations themselves do not change, so the S the gate compares
against is scaled by 1/c (the file's ``[filter] gate_scale``, the guard's
``innovation_variance_scale``): the gate and its innovation spread keep the
decisions they had, and the estimates are those of the unscaled shape.
Consistency: the normalised innovation squared :math:`y^2/S` of each row
against the 95 % band of :math:`\chi^2_1`, and the share of samples whose
error lies within :math:`\pm 2\sigma`.

Example
-------
>>> result = tune(vehicle, (read_log("drive.csv"),))
>>> result.tuning  # q, r_s, r_c
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import (
    NOISE_DENSITIES,
    TUNING,
    UPDATE_ROWS,
    TwoStageKF,
    step_function,
)
from wheelload.models.vehicle import FilterTuning, Vehicle

SETTLE = 1.0  # s, start of each log left out of the objective (initial covariance)
SPAN = 1e3  # each density stays within input / SPAN .. input * SPAN
COVERAGE_TARGET = 0.95  # share of errors within +-2 sigma for a Gaussian error
NIS_BAND = (stats.chi2.ppf(0.025, 1), stats.chi2.ppf(0.975, 1))  # 95 % band of chi^2_1
#: Tuning entries that open the innovation gate for the likelihood (out of reach).
GATE_OPEN = {"innovation_gate": 1e300, "gate_release_time": 1e300}
_VARIANCE_SCALE = TUNING.index("innovation_variance_scale")


def with_tuning(vehicle: Vehicle, tuning: np.ndarray, gate_scale: float | None = None) -> Vehicle:
    """The vehicle with its ``[filter]`` noise densities replaced (``NOISE_DENSITIES`` order)
    and, if given, its ``gate_scale``."""
    tuning = np.asarray(tuning, float)
    current: FilterTuning = vehicle.filter
    return vehicle.replace(
        filter=dataclasses.replace(
            current,
            process_noise_density=float(tuning[0]),
            suspension_noise_density=float(tuning[1]),
            constraint_noise_density=tuple(float(x) for x in tuning[2:5]),
            gate_scale=current.gate_scale if gate_scale is None else float(gate_scale),
        )
    )


@dataclass(frozen=True, kw_only=True)
class Consistency:
    """Filter consistency on a set of logs."""

    nis_mean: tuple[float, ...]  # mean y^2/S per update row (1 when consistent)
    nis_in_band: tuple[float, ...]  # share of y^2/S inside the 95 % chi^2_1 band (0.95)
    coverage: float  # share of (sample, wheel) errors within +-2 sigma (nan: no reference)
    rmse: float  # pooled RMSE [N] (nan: no reference)
    sigma_error_correlation: float  # Pearson r of sigma and |error| (nan: no reference)
    gated: float  # share of available update rows the innovation gate skipped


class FilterRuns:
    """Runs the filter of one vehicle over logs with any tuning (one compiled step)."""

    def __init__(self, vehicle: Vehicle, logs: tuple[Signals, ...]) -> None:
        if not logs:
            raise ValueError("no logs to tune on")
        self.vehicle = vehicle
        self.logs = logs
        self._step = step_function()
        # The filter the written file runs: its interval and guard settings (TwoStageKF's own).
        self._kf = TwoStageKF(vehicle, step=self._step)
        self._base = self._kf.tuning.copy()
        self._gate_open = self._base.copy()
        for name, value in GATE_OPEN.items():
            self._gate_open[TUNING.index(name)] = value

    def run(self, tuning: np.ndarray, *, gate_factor: float = 1.0, gate_open: bool = False):
        """Estimates and innovations of every log with the noise densities ``tuning``
        (:data:`NOISE_DENSITIES` order; interval and guards as the filter's own, the
        S the gate compares against times ``gate_factor``, or the gate opened with
        ``gate_open``)."""
        densities = np.asarray(tuning, float)
        if densities.shape != (len(NOISE_DENSITIES),):
            raise ValueError(f"give the {len(NOISE_DENSITIES)} noise densities {NOISE_DENSITIES}")
        full = (self._gate_open if gate_open else self._base).copy()
        full[_VARIANCE_SCALE] *= 1.0 if gate_open else gate_factor
        full[: len(NOISE_DENSITIES)] = densities
        self._kf.tuning = full
        return [self._kf.run_innovations(signals) for signals in self.logs]

    def negative_log_likelihood(self, tuning: np.ndarray) -> float:
        """Minus the innovation log likelihood, innovation gate open (every row with inputs)."""
        total = 0.0
        for signals, (_, inn) in zip(self.logs, self.run(tuning, gate_open=True)):
            keep = (inn.variance > 0) & (signals.t - signals.t[0] >= SETTLE)[:, None]
            S, y = inn.variance[keep], inn.innovation[keep]
            total += 0.5 * float(np.sum(np.log(2 * np.pi * S) + y**2 / S))
        return total

    def pooled_rmse(self, tuning: np.ndarray, gate_factor: float = 1.0) -> float:
        errors = []
        for signals, (estimate, _) in zip(self.logs, self.run(tuning, gate_factor=gate_factor)):
            if signals.reference is None:
                raise ValueError(f"{signals.source}: no reference loads fz_* for an RMSE tuning")
            keep = signals.t - signals.t[0] >= SETTLE
            error = estimate.loads[keep] - signals.reference[keep]
            errors.append(error[np.isfinite(error)])
        return float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))

    def consistency(self, tuning: np.ndarray, gate_factor: float = 1.0) -> Consistency:
        """NIS, ±2σ coverage, RMSE, σ–|error| correlation and gated share over the logs."""
        nis, inside, covered, squared, pairs = [], [], [], [], []
        gated, available = 0, 0
        for signals, (estimate, inn) in zip(self.logs, self.run(tuning, gate_factor=gate_factor)):
            settled = signals.t - signals.t[0] >= SETTLE
            present = (inn.variance > 0) & settled[:, None]
            gated += int(np.sum(present & ~inn.used))
            available += int(np.sum(present))
            keep = inn.used & present
            ratio = np.where(keep, inn.innovation**2 / np.where(keep, inn.variance, 1.0), np.nan)
            nis.append(ratio)
            if signals.reference is not None:
                error = (estimate.loads - signals.reference)[settled]
                sigma = estimate.std[settled]
                ok = np.isfinite(error)
                covered.append(np.abs(error[ok]) <= 2 * sigma[ok])
                squared.append(error[ok] ** 2)
                pairs.append(np.column_stack([sigma[ok], np.abs(error[ok])]))
        ratio = np.vstack(nis)
        for row in range(ratio.shape[1]):
            values = ratio[:, row][np.isfinite(ratio[:, row])]
            inside.append(
                float(np.mean((values >= NIS_BAND[0]) & (values <= NIS_BAND[1])))
                if values.size
                else np.nan
            )
        return Consistency(
            nis_mean=tuple(float(np.nanmean(ratio[:, r])) for r in range(ratio.shape[1])),
            nis_in_band=tuple(inside),
            coverage=float(np.mean(np.concatenate(covered))) if covered else np.nan,
            rmse=float(np.sqrt(np.mean(np.concatenate(squared)))) if squared else np.nan,
            sigma_error_correlation=_correlation(np.vstack(pairs)) if pairs else np.nan,
            gated=gated / available if available else 0.0,
        )

    def coverage(self, tuning: np.ndarray, gate_factor: float = 1.0) -> float:
        return self.consistency(tuning, gate_factor).coverage

    def calibrate(self, tuning: np.ndarray, target: float = COVERAGE_TARGET) -> float:
        """Factor c on all densities giving ``target`` ±2σ coverage on the logs' references.

        Scaling Q, R_s and R_c together by c, with the gate's S by 1/c,
        leaves the gain, the gate's decisions and the estimates unchanged and
        scales P by c: only the reported σ moves.
        """
        low, high = np.log(1e-4), np.log(1e4)
        for _ in range(40):
            middle = 0.5 * (low + high)
            factor = np.exp(middle)
            if self.coverage(tuning * factor, 1.0 / factor) < target:
                low = middle
            else:
                high = middle
        return float(np.exp(0.5 * (low + high)))


def _correlation(pairs: np.ndarray) -> float:
    """Pearson correlation of the two columns (0 when either is constant)."""
    spread = np.std(pairs, axis=0)
    if np.any(spread <= 0):
        return 0.0
    return float(np.corrcoef(pairs[:, 0], pairs[:, 1])[0, 1])


@dataclass(frozen=True, kw_only=True)
class TuningResult:
    initial: np.ndarray  # NOISE_DENSITIES order
    likelihood: np.ndarray  # maximum-likelihood tuning
    rmse: np.ndarray | None  # RMSE-minimising tuning (with reference loads)
    shape: np.ndarray  # the shape written: ``likelihood``, or ``initial`` when it does better
    scale: float  # calibration factor applied to ``shape`` (1 without references)
    evaluations: int

    @property
    def gate_factor(self) -> float:
        """Factor on the gate's S that goes with :attr:`tuned` (1 / :attr:`scale`)."""
        return 1.0 / self.scale

    @property
    def tuned(self) -> np.ndarray:
        """The tuning written to the file: the chosen shape, calibrated when possible."""
        return self.shape * self.scale

    @property
    def shape_source(self) -> str:
        """Which shape was written: ``"likelihood"`` or ``"input"``."""
        return "input" if self.shape is self.initial else "likelihood"


def _minimise(
    objective, start: np.ndarray, iterations: int, span: np.ndarray
) -> tuple[np.ndarray, int]:
    """Nelder-Mead in log-parameters within ``span`` (pairs of bounds)."""
    result = optimize.minimize(
        lambda log_tuning: objective(np.exp(log_tuning)),
        np.log(start),
        method="Nelder-Mead",
        bounds=np.log(span),
        options={"maxiter": iterations, "xatol": 1e-3, "fatol": 1e-4, "adaptive": True},
    )
    return np.exp(result.x), int(result.nfev)


def tune(runs: FilterRuns, start: np.ndarray, *, references: bool, iterations: int = 400):
    """Maximum-likelihood tuning; with ``references`` also the RMSE-minimising one and the
    coverage calibration of the likelihood tuning (its estimates unchanged)."""
    span = np.column_stack([start / SPAN, start * SPAN])
    likelihood, count = _minimise(runs.negative_log_likelihood, start, iterations, span)
    rmse, shape, scale = None, likelihood, 1.0
    if references:
        rmse, more = _minimise(runs.pooled_rmse, likelihood, iterations, span)
        count += more
        # Each shape calibrated to the coverage target (the gate's S scaled with it, so
        # the estimates are the shape's own with the file's guards); the lower pooled RMSE
        # is written.
        scored = []
        for candidate in (likelihood, start):
            factor = runs.calibrate(candidate)
            scored.append((runs.pooled_rmse(candidate), candidate, factor))
        _, shape, scale = min(scored, key=lambda entry: entry[0])
    return TuningResult(
        initial=start,
        likelihood=likelihood,
        rmse=rmse,
        shape=shape,
        scale=scale,
        evaluations=count,
    )


def tuned_vehicle(vehicle: Vehicle, result: TuningResult) -> Vehicle:
    """``vehicle`` with the tuning written by ``wheelload tune``: densities and gate scale."""
    return with_tuning(vehicle, result.tuned, vehicle.filter.gate_scale * result.gate_factor)


__all__ = [
    "NOISE_DENSITIES",
    "UPDATE_ROWS",
    "Consistency",
    "FilterRuns",
    "TuningResult",
    "tune",
    "tuned_vehicle",
    "with_tuning",
]
