r"""Tuning of the two-stage KF's noise densities: innovation likelihood and reference RMSE.

Prediction-error method (Mehra 1970; Ljung, *System Identification*, §7):
the filter's sequential innovations :math:`y_{k,i}` with variances
:math:`S_{k,i}` (outputs of the filter step itself) are independent normals
under the model, so the tuning :math:`\theta = \log(q, r_s, r_{c,1..3}, r_{sv}, r_{sh},
r_{ca,1..3})` (constant and input-dependent densities,
:mod:`wheelload.models.measurement_noise`) maximises

.. math:: \ell(\theta) = -\tfrac12 \sum_{k,i} \big(\log 2\pi S_{k,i} + y_{k,i}^2 / S_{k,i}\big)

over every row whose inputs are present (Nelder-Mead in the log-parameters, each constant
density within a factor 1000 of the input: the pseudo-measurement error is correlated in
time, and unbounded the white-noise likelihood may drive ``r_s`` to zero). An
input-dependent density is kept only if it raises :math:`\ell` by 2 (a likelihood-ratio
test at about 5 %), else it is 0 (constant noise). The likelihood is evaluated with the
innovation gate open: a gate removes exactly the large innovations the likelihood needs.
Everything else (the estimates, the coverage, the RMSE) runs with the guard settings the
filter of the written file runs with (:class:`~wheelload.estimators.TwoStageKF`'s own).

Shape that generalises: a shape fitted on a few manoeuvres must not wreck another. The
likelihood is fitted again leaving each log out; a ratio of q or of an equilibrium row's
r_c to r_s is taken from the likelihood only if those fits and the fit on all logs agree
on it within a factor 2,
else it stays the input file's (the relative trust in the suspension and the equilibrium
rows depends on the manoeuvre: on the sports car's lane change and steady turn the fits
differ by 3-30x). Along the log-parameter line from the input shape to that one, the
largest step whose per-log RMSE stays within 2 % of the input's on every tuning log, both
in sample and for the fits that left the log out, is written. With reference loads the
written shape is scaled as a whole by c so that ±2σ covers 95 % of the error: the model
errors are correlated in time, which the white-noise likelihood cannot see. Scaling leaves
the gain unchanged and scales P and every innovation variance S by c; the innovations
themselves do not change, so the S the gate compares against is scaled by 1/c (the file's
``[filter] gate_scale``, the guard's ``innovation_variance_scale``): the gate and its
innovation spread keep the decisions they had, and the estimates are those of the
unscaled shape. With references the tuning that minimises the pooled RMSE is also
reported. Consistency: the normalised innovation squared :math:`y^2/S` of each row against
the 95 % band of :math:`\chi^2_1`, and the share of samples whose error lies within
:math:`\pm 2\sigma`.

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

from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.step_cache import UPDATE_ROWS
from wheelload.estimators.kf.tuning import (
    NOISE_DENSITIES,
    TUNED_DENSITIES,
    TUNING,
    noise_densities,
    with_filter_sigma,
)
from wheelload.estimators.kf.two_stage import FileCheck, TwoStageKF
from wheelload.estimators.types import Signals
from wheelload.models.measurement_noise import INPUT_DENSITIES
from wheelload.models.vehicle.description import FilterTuning, Vehicle

SETTLE = 1.0  # s, start of each log left out of the objective (initial covariance)
SPAN = 1e3  # each density stays within input / SPAN .. input * SPAN
COVERAGE_TARGET = 0.95  # share of errors within +-2 sigma for a Gaussian error
NIS_BAND = (stats.chi2.ppf(0.025, 1), stats.chi2.ppf(0.975, 1))  # 95 % band of chi^2_1
#: Tuning entries that open the innovation gate for the likelihood (out of reach).
GATE_OPEN = {"innovation_gate": 1e300, "gate_release_time": 1e300}
_VARIANCE_SCALE = TUNING.index("innovation_variance_scale")
_DENSITY_INDEX = TUNING.indices(TUNED_DENSITIES)
#: Input size at which an input-dependent density starts its fit, adding a tenth of the
#: constant density it goes with: damper velocity 0.1 m/s, accelerations 2 m/s^2.
INPUT_SCALE = {
    "suspension_noise_rate_density": ("suspension_noise_density", 0.1),
    "suspension_noise_hub_density": ("suspension_noise_density", 2.0),
    "constraint_noise_vertical_acceleration": ("constraint_noise_vertical", 2.0),
    "constraint_noise_pitch_acceleration": ("constraint_noise_pitch", 2.0),
    "constraint_noise_roll_acceleration": ("constraint_noise_roll", 2.0),
}
INPUT_SPAN = 1e6  # an input-dependent density may fall to start / INPUT_SPAN (then off)
#: Blend steps t along the log-parameter line from the input shape (0) to the likelihood's (1).
BLENDS = (1.0, 0.75, 0.5, 0.25, 0.0)
RMSE_TOLERANCE = 1.02  # a blend is taken only within 2 % of the input's RMSE on every log


def with_tuning(vehicle: Vehicle, tuning: np.ndarray, gate_scale: float | None = None) -> Vehicle:
    """The vehicle with its ``[filter]`` noise densities replaced (``TUNED_DENSITIES`` order;
    the first five alone keep the file's input-dependent ones) and, if given, ``gate_scale``."""
    tuning = np.asarray(tuning, float)
    current: FilterTuning = vehicle.filter
    if tuning.shape == (len(NOISE_DENSITIES),):
        tuning = np.concatenate([tuning, current.input_densities()])
    named = dict(zip(TUNED_DENSITIES, map(float, tuning), strict=True))
    return vehicle.replace(
        filter=dataclasses.replace(
            current,
            process_noise_density=named["process_noise_density"],
            suspension_noise_density=named["suspension_noise_density"],
            constraint_noise_density=tuple(
                named[f"constraint_noise_{row}"] for row in ("vertical", "pitch", "roll")
            ),
            suspension_noise_rate_density=named["suspension_noise_rate_density"],
            suspension_noise_hub_density=named["suspension_noise_hub_density"],
            constraint_noise_acceleration_density=tuple(
                named[f"constraint_noise_{row}_acceleration"]
                for row in ("vertical", "pitch", "roll")
            ),
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
    """Runs the filter of one vehicle over logs with any tuning (one compiled step).

    ``filter_sigma``: σ (coverage, correlation) is the filter's own sqrt(P_ii), on which
    the densities are calibrated; else the reported σ of the vehicle file.
    """

    def __init__(
        self,
        vehicle: Vehicle,
        logs: tuple[Signals, ...],
        *,
        filter_sigma: bool = True,
        checks: list[FileCheck | None] | None = None,
    ) -> None:
        if not logs:
            raise ValueError("no logs to tune on")
        self.vehicle = vehicle
        self.logs = logs
        self._step = step_function()
        # The filter the written file runs: its interval and guard settings (TwoStageKF's own).
        self._kf = TwoStageKF(vehicle, step=self._step)
        self._base = self._kf.tuning.copy()
        if filter_sigma:
            # The densities are calibrated on the filter's own sigma, sqrt(P_ii); the
            # reported sigma's other terms are fitted after (sigma_fit.py).
            self._base = with_filter_sigma(self._base)
        self._gate_open = self._base.copy()
        for name, value in GATE_OPEN.items():
            self._gate_open[TUNING.index(name)] = value
        # The file is checked against each log once, with the file's own tuning: the check
        # reads the vehicle file, not the densities, and each run applies its finding.
        self._checks = checks or [
            self._kf.file_check(signals) if self._kf.check_file else None for signals in logs
        ]

    def run(self, tuning: np.ndarray, *, gate_factor: float = 1.0, gate_open: bool = False):
        """Estimates and innovations of every log with the noise densities ``tuning``
        (:data:`TUNED_DENSITIES` order; interval and guards as the filter's own, the
        S the gate compares against times ``gate_factor``, or the gate opened with
        ``gate_open``)."""
        densities = np.asarray(tuning, float)
        if densities.shape == (len(NOISE_DENSITIES),):  # constant densities: the file's others
            densities = np.concatenate([densities, self.vehicle.filter.input_densities()])
        if densities.shape != (len(TUNED_DENSITIES),):
            raise ValueError(f"give the {len(TUNED_DENSITIES)} noise densities {TUNED_DENSITIES}")
        full = (self._gate_open if gate_open else self._base).copy()
        full[_VARIANCE_SCALE] *= 1.0 if gate_open else gate_factor
        full[_DENSITY_INDEX] = densities
        self._kf.tuning = full
        return [
            self._kf.run_innovations(signals, checked=checked)
            for signals, checked in zip(self.logs, self._checks, strict=True)
        ]

    def negative_log_likelihood(self, tuning: np.ndarray) -> float:
        """Minus the innovation log likelihood, innovation gate open (every row with inputs)."""
        total = 0.0
        for signals, (_, inn) in zip(self.logs, self.run(tuning, gate_open=True)):
            keep = (inn.variance > 0) & (signals.t - signals.t[0] >= SETTLE)[:, None]
            S, y = inn.variance[keep], inn.innovation[keep]
            total += 0.5 * float(np.sum(np.log(2 * np.pi * S) + y**2 / S))
        return total

    def log_rmse(self, tuning: np.ndarray) -> np.ndarray:
        """Pooled RMSE [N] of each log (guards on), after :data:`SETTLE`."""
        values = []
        for signals, (estimate, _) in zip(self.logs, self.run(tuning)):
            keep = signals.t - signals.t[0] >= SETTLE
            error = (estimate.loads[keep] - signals.reference[keep]).ravel()
            values.append(np.sqrt(np.mean(error[np.isfinite(error)] ** 2)))
        return np.array(values)

    def subset(self, keep: list[int]) -> FilterRuns:
        """The same filter over the logs at ``keep`` (with the filter's own sigma)."""
        return FilterRuns(
            self.vehicle,
            tuple(self.logs[k] for k in keep),
            checks=[self._checks[k] for k in keep],
        )

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
        """NIS, ±2σ coverage, RMSE, σ–``|error|`` correlation and gated share over the logs."""
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
            nis_mean=tuple(_finite_mean(ratio[:, r]) for r in range(ratio.shape[1])),
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
class BlendScore:
    """RMSE ratios to the input tuning of one blend step ``t`` (1: the likelihood shape)."""

    t: float
    held_out: tuple[float, ...]  # per tuning log, shape fitted on the other logs
    in_sample: tuple[float, ...]  # per tuning log, shape fitted on all of them

    @property
    def accepted(self) -> bool:
        """No log more than :data:`RMSE_TOLERANCE` times the input tuning's RMSE."""
        return max((*self.held_out, *self.in_sample), default=1.0) <= RMSE_TOLERANCE


@dataclass(frozen=True, kw_only=True)
class TuningResult:
    initial: np.ndarray  # TUNED_DENSITIES order
    likelihood: np.ndarray  # maximum-likelihood tuning
    folds: tuple[np.ndarray, ...]  # likelihood fits leaving one log out each (>= 2 logs)
    agreed: tuple[str, ...]  # RATIOS the fold fits agree on (taken from the likelihood)
    robust: np.ndarray  # ``likelihood`` with the other ratios the input's
    rmse: np.ndarray | None  # RMSE-minimising tuning (with reference loads)
    shape: np.ndarray  # the shape written: the blend ``blend`` of input and ``robust``
    blend: float  # 0: the input shape, 1: the likelihood shape
    scores: tuple[BlendScore, ...]  # the blend steps tried (with references)
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
        """Which shape was written: ``"likelihood"``, ``"input"`` or ``"blend t=.."``."""
        if self.blend >= 1.0:
            return "likelihood"
        return "input" if self.blend <= 0.0 else f"blend t={self.blend:g}"


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


def blend(start: np.ndarray, target: np.ndarray, t: float) -> np.ndarray:
    r"""The point ``t`` of the way from ``start`` to ``target`` on the log-parameter line:
    :math:`r^{1-t} r_\star^{t}`; a density that is 0 in ``start`` (an input-dependent term
    off) grows linearly, :math:`t\,r_\star`."""
    start, target = np.asarray(start, float), np.asarray(target, float)
    if t in (0.0, 1.0):  # the end points exactly
        return (start if t == 0.0 else target).copy()
    positive = (start > 0) & (target > 0)
    geometric = np.exp((1 - t) * np.log(np.where(positive, start, 1.0))
                       + t * np.log(np.where(positive, target, 1.0)))  # fmt: skip
    return np.where(positive, geometric, (1 - t) * start + t * target)


def _search_start(start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starting point and bounds of the log-parameter search: an input-dependent density
    that is 0 starts where it adds a tenth of its constant density at :data:`INPUT_SCALE`."""
    begin = np.array(start, float)
    low, high = begin / SPAN, begin * SPAN
    for name in INPUT_DENSITIES:
        k = TUNED_DENSITIES.index(name)
        base, size = INPUT_SCALE[name]
        if begin[k] <= 0:
            begin[k] = 0.1 * start[TUNED_DENSITIES.index(base)] / size**2
        low[k], high[k] = begin[k] / INPUT_SPAN, begin[k] * SPAN
    return begin, np.column_stack([low, high])


def _maximum_likelihood(runs: FilterRuns, start: np.ndarray, iterations: int):
    """Maximum likelihood of the innovations; an input-dependent density whose term does not
    raise the log likelihood by 2 (a likelihood-ratio test at about 5 %, one degree of
    freedom) is switched off (0)."""
    begin, span = _search_start(start)
    best, count = _minimise(runs.negative_log_likelihood, begin, iterations, span)
    value = runs.negative_log_likelihood(best)
    for name in INPUT_DENSITIES:
        k = TUNED_DENSITIES.index(name)
        trial = best.copy()
        trial[k] = 0.0
        nll = runs.negative_log_likelihood(trial)
        count += 1
        if nll - value < 2.0:
            best, value = trial, nll
    return best, count


#: Ratios of densities the likelihood sets only when the logs agree on them (see
#: :func:`agreed_ratios`): each to the suspension density r_s.
RATIOS = (
    "process_noise_density",
    "constraint_noise_vertical",
    "constraint_noise_pitch",
    "constraint_noise_roll",
)
RATIO_AGREEMENT = 2.0  # largest factor between the logs' own fits of a ratio that is taken
_RS = TUNED_DENSITIES.index("suspension_noise_density")


def fold_fits(runs: FilterRuns, start: np.ndarray, iterations: int):
    """Maximum-likelihood tuning of each leave-one-log-out fold: ``[(held_out_runs, fit)]``
    (empty with one log) and the evaluations spent."""
    n, folds, count = len(runs.logs), [], 0
    if n > 1:
        for k in range(n):
            others = runs.subset([j for j in range(n) if j != k])
            fit, more = _maximum_likelihood(others, start, iterations)
            count += more
            folds.append((runs.subset([k]), fit))
    return folds, count


def agreed_ratios(fits: list[np.ndarray]) -> tuple[str, ...]:
    """The :data:`RATIOS` whose value (to r_s) the fits (the fit on all logs and those
    leaving one out) agree on within :data:`RATIO_AGREEMENT`; none with fewer than three
    fits (two logs)."""
    if len(fits) < 3:
        return ()
    agreed = []
    for name in RATIOS:
        k = TUNED_DENSITIES.index(name)
        values = [fit[k] / fit[_RS] for fit in fits]
        if max(values) <= RATIO_AGREEMENT * min(values):
            agreed.append(name)
    return tuple(agreed)


def with_input_ratios(start: np.ndarray, fit: np.ndarray, agreed: tuple[str, ...]) -> np.ndarray:
    """``fit`` with each :data:`RATIOS` entry not in ``agreed`` set to the input's ratio to
    r_s (at the fit's r_s); an equilibrium row's input-dependent density moves with it."""
    shape = np.array(fit, float)
    for name in RATIOS:
        if name in agreed:
            continue
        k = TUNED_DENSITIES.index(name)
        value = fit[_RS] * start[k] / start[_RS]
        if name.startswith("constraint_noise_"):
            gain = TUNED_DENSITIES.index(f"{name}_acceleration")
            shape[gain] = fit[gain] * value / fit[k]
        shape[k] = value
    return shape


def choose_blend(runs: FilterRuns, start: np.ndarray, likelihood: np.ndarray, folds):
    """The largest blend step t (:data:`BLENDS`) of input and likelihood shape that leaves
    every tuning log within :data:`RMSE_TOLERANCE` of the input's RMSE, both fitted on all
    logs (in sample) and, leaving each log out in turn, fitted on the others (held out:
    ``folds`` from :func:`fold_fits`, shaped as ``likelihood`` is).

    Returns ``(t, scores)``; t = 0 (the input shape) always passes.
    """
    base = runs.log_rmse(start)
    scores = []
    for t in BLENDS:
        in_sample = runs.log_rmse(blend(start, likelihood, t)) / base
        held_out = [
            float(held.log_rmse(blend(start, fold, t))[0] / base[k])
            for k, (held, fold) in enumerate(folds)
        ]
        scores.append(BlendScore(t=t, held_out=tuple(held_out), in_sample=tuple(in_sample)))
    chosen = next(score.t for score in scores if score.accepted or score.t == 0.0)
    return chosen, tuple(scores)


def tune(
    runs: FilterRuns, start: np.ndarray, *, references: bool, iterations: int = 400
) -> TuningResult:
    """Maximum-likelihood tuning (constant and input-dependent densities) shaped so that it
    generalises: the ratios of q and r_c to r_s the leave-one-log-out fits do not agree on
    stay the input's (:func:`agreed_ratios`); with ``references`` also the RMSE-minimising
    tuning, the blend of input and likelihood shape no tuning log objects to
    (:func:`choose_blend`) and its coverage calibration (its estimates unchanged)."""
    start = np.asarray(start, float)
    if start.shape == (len(NOISE_DENSITIES),):
        start = np.concatenate([start, runs.vehicle.filter.input_densities()])
    likelihood, count = _maximum_likelihood(runs, start, iterations)
    folds, more = fold_fits(runs, likelihood, iterations)
    count += more
    agreed = agreed_ratios([likelihood, *[fit for _, fit in folds]])
    robust = with_input_ratios(start, likelihood, agreed)
    rmse, shape, scale, t, scores = None, robust, 1.0, 1.0, ()
    if references:
        begin, span = _search_start(start)
        rmse, more = _minimise(runs.pooled_rmse, np.where(likelihood > 0, likelihood, begin),
                               iterations, span)  # fmt: skip
        count += more
        shaped = [(held, with_input_ratios(start, fit, agreed)) for held, fit in folds]
        t, scores = choose_blend(runs, start, robust, shaped)
        # The chosen shape calibrated to the coverage target (the gate's S scaled with it,
        # so the estimates are the shape's own with the file's guards).
        shape = blend(start, robust, t)
        scale = runs.calibrate(shape)
    return TuningResult(
        initial=start,
        likelihood=likelihood,
        folds=tuple(fit for _, fit in folds),
        agreed=agreed,
        robust=robust,
        rmse=rmse,
        shape=shape,
        blend=t,
        scores=scores,
        scale=scale,
        evaluations=count,
    )


def tuned_vehicle(vehicle: Vehicle, result: TuningResult) -> Vehicle:
    """``vehicle`` with the tuning written by ``wheelload tune``: densities and gate scale."""
    return with_tuning(vehicle, result.tuned, vehicle.filter.gate_scale * result.gate_factor)


__all__ = [
    "NOISE_DENSITIES",
    "TUNED_DENSITIES",
    "TUNING",
    "UPDATE_ROWS",
    "noise_densities",
    "BlendScore",
    "blend",
    "agreed_ratios",
    "choose_blend",
    "fold_fits",
    "with_input_ratios",
    "Consistency",
    "FilterRuns",
    "TuningResult",
    "tune",
    "tuned_vehicle",
    "with_tuning",
]


def _finite_mean(values: np.ndarray) -> float:
    """Mean of the finite values; NaN (no warning) where a row never ran."""
    finite = values[np.isfinite(values)]
    return float(finite.mean()) if finite.size else np.nan
