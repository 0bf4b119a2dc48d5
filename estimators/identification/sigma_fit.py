r"""Calibration of the reported-sigma model on logs with reference loads.

The model (:mod:`wheelload.estimators.kf.reported_std`) is
:math:`\sigma_i^2 = \sum_k w_k g_{ik}^2` with :math:`w_k = c_k^2 \ge 0` and
:math:`g_{i0} = \sqrt{P_{ii}}`. The gain never sees it, so the features g of a log do not
depend on the coefficients: the filter's own step gives them, run with each
:math:`c_k = 1` alone (:math:`\sigma = g_k`); no second copy of the features. The weights
maximise the Gaussian likelihood of the errors :math:`e = \hat F_z - F_z`, each log
weighing the same,

.. math:: \min_{w \ge 0} \sum_{n,i} \log \sigma_{ni}^2 + e_{ni}^2 / \sigma_{ni}^2

(L-BFGS-B), then scaled as a whole so that ±2σ covers :data:`COVERAGE_TARGET` of the errors
(the errors are correlated in time and heavier-tailed than a normal, which the likelihood
alone does not see); last, the weights are moved so that each log's coverage lies in
:data:`COVERAGE_BAND` where the features allow (the likelihood plus a penalty on each log's
distance from the band): one scale cannot serve a clean log and a noisy one at once.

Example
-------
>>> data = sigma_data(TwoStageKF(vehicle), signals)
>>> coefficients = fit_sigma([data]).coefficients
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy import optimize, special

from wheelload.estimators.kf.tuning import SIGMA_TUNING
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.types import Signals
from wheelload.models.vehicle.description import SIGMA_KEYS, Vehicle

SETTLE = 1.0  # s, start of each log left out (initial covariance)
COVERAGE_TARGET = 0.95  # share of errors within +-2 sigma
COVERAGE_BAND = (0.91, 0.98)  # each log's share within +-2 sigma, where the features allow
BAND_PENALTY = 30.0  # weight of a log's squared distance from the band beside the likelihood
#: Least coefficient of the filter's own sigma sqrt(P_ii): P grows where rows are missing
#: (start-up, a gap, no travel), which no other feature sees.
COVARIANCE_SHARE = 0.05


@dataclass(frozen=True, kw_only=True, eq=False)
class SigmaData:
    """Per settled sample and wheel: the error [N], P_ii [N^2] and the features g (last axis
    :data:`SIGMA_KEYS`)."""

    error: np.ndarray  # (n, w): the w wheels with a reference load
    features: np.ndarray  # (n, w, K)

    def std(self, coefficients: np.ndarray) -> np.ndarray:
        """The reported sigma (n, 4) with ``coefficients`` (:data:`SIGMA_KEYS` order)."""
        weights = np.asarray(coefficients, float) ** 2
        return np.sqrt(self.features**2 @ weights)

    def thinned(self, stride: int) -> SigmaData:
        """Every ``stride``-th sample."""
        return SigmaData(error=self.error[::stride], features=self.features[::stride])


def sigma_data(kf: TwoStageKF, signals: Signals) -> SigmaData:
    """Errors and σ features of the filter ``kf`` on a log with reference loads."""
    if signals.reference is None:
        raise ValueError(f"{signals.source}: no reference loads fz_*: cannot calibrate sigma")
    base = np.array(kf.tuning, float)
    settled = signals.t - signals.t[0] >= SETTLE
    features = []
    try:
        for unit in np.eye(len(SIGMA_KEYS)):
            kf.tuning = base.copy()
            kf.tuning[SIGMA_TUNING] = unit
            estimate = kf.run(signals)
            features.append(estimate.std[settled])
    finally:
        kf.tuning = base
    # The wheels with a reference (front transducers only: FL, FR), each sample where all
    # of them have one; the others are not scored.
    wheels = signals.reference_present
    error = (estimate.loads[settled] - signals.reference[settled])[:, wheels]
    keep = np.all(np.isfinite(error), axis=1)
    features = np.stack(features, axis=2)[:, wheels]
    return SigmaData(error=error[keep], features=features[keep])


@dataclass(frozen=True, kw_only=True)
class SigmaFit:
    coefficients: np.ndarray  # SIGMA_KEYS order, c_k >= 0
    scale: float  # factor on the likelihood's variance for the pooled coverage target
    coverage: float  # on the fit's data
    correlation: float  # Pearson r of sigma and |error| on the fit's data
    # Each log's coverage with the model fitted on the other logs (empty with one log):
    # what the calibration promises a log it has not seen.
    held_out: tuple[float, ...] = ()


def scores(data: list[SigmaData], coefficients: np.ndarray) -> tuple[float, float]:
    """``(coverage, r)``: share of errors within ±2σ and the Pearson r of σ and ``|error|``."""
    std = np.concatenate([d.std(coefficients).ravel() for d in data])
    error = np.abs(np.concatenate([d.error.ravel() for d in data]))
    if not error.size:
        return float("nan"), float("nan")
    coverage = float(np.mean(error <= 2 * std))
    if np.std(std) <= 0 or np.std(error) <= 0:
        return coverage, 0.0
    return coverage, float(np.corrcoef(std, error)[0, 1])


def fit_sigma(
    data: list[SigmaData],
    target: float = COVERAGE_TARGET,
    held: np.ndarray | None = None,
    free: tuple[str, ...] | None = None,
) -> SigmaFit:
    """Maximum-likelihood weights, scaled to the ±2σ coverage ``target`` (module doc).

    Only the keys ``free`` (default: every key) are fitted, beside the others held at
    ``held`` (default 0); a feature that is 0 on every sample (no log without travel, say)
    cannot be fitted and is held too.
    """
    data = [d for d in data if d.error.size]
    if not data:
        raise ValueError("no logs with reference loads to calibrate sigma on")
    seen = np.any([np.any(d.features != 0, axis=(0, 1)) for d in data], axis=0)
    fitted = seen & np.isin(SIGMA_KEYS, SIGMA_KEYS if free is None else free)
    coefficients = np.zeros(len(SIGMA_KEYS)) if held is None else np.array(held, float)
    coefficients[fitted] = 0.0
    # The held terms' variance, per sample and wheel (N^2).
    offsets = [d.std(coefficients).ravel() ** 2 for d in data]
    reduced = [SigmaData(error=d.error, features=d.features[..., fitted]) for d in data]
    names = [SIGMA_KEYS[k] for k in np.flatnonzero(fitted)]
    coefficients[fitted], scale = _fit(reduced, offsets, target, names)
    coverage, correlation = scores(data, coefficients)
    return SigmaFit(
        coefficients=coefficients, scale=scale, coverage=coverage, correlation=correlation
    )


def _fit(data: list[SigmaData], offsets: list[np.ndarray], target: float, names):
    """``(coefficients, scale)`` of :func:`fit_sigma` on the features ``names`` (each seen
    on some sample) beside the held terms' variances ``offsets`` (per log, raveled)."""
    e2 = np.concatenate([d.error.ravel() ** 2 for d in data])
    G = np.concatenate([d.features.reshape(-1, len(names)) ** 2 for d in data])
    held = np.concatenate(offsets)
    # Every log weighs the same, whatever its length.
    share = np.concatenate([np.full(d.error.size, 1.0 / d.error.size) for d in data])
    share /= np.sum(share)
    # Each weight in units of the mean squared error per mean squared feature; the floor
    # keeps every variance positive.
    unit = np.mean(e2) / np.fmax(np.mean(G, axis=0), 1e-300)
    G = G * unit
    lower = np.zeros(len(names))
    if "sigma_floor" in names:
        lower[names.index("sigma_floor")] = 1e-6
    if "sigma_covariance" in names:
        lower[names.index("sigma_covariance")] = COVARIANCE_SHARE**2 / unit[0]
    bounds = [(low, None) for low in lower]

    def objective(w: np.ndarray) -> tuple[float, np.ndarray]:
        v = np.fmax(G @ w + held, 1e-300)
        value = float(np.sum(share * (np.log(v) + e2 / v)))
        gradient = G.T @ (share * (1.0 / v - e2 / v**2))
        return value, gradient

    start = np.full(len(names), 1.0 / len(names))
    found = optimize.minimize(objective, start, jac=True, method="L-BFGS-B", bounds=bounds)
    variance = G @ found.x
    std_error = np.sqrt(e2)
    low, high = np.log(1e-3), np.log(1e3)
    for _ in range(50):
        middle = 0.5 * (low + high)
        covered = np.mean(std_error <= 2 * np.sqrt(np.exp(middle) * variance + held))
        low, high = (middle, high) if covered < target else (low, middle)
    scale = float(np.exp(0.5 * (low + high)))
    weights = _within_band(data, offsets, found.x * scale * unit, lower * unit)
    return np.sqrt(weights), scale


def _within_band(
    data: list[SigmaData], offsets: list[np.ndarray], weights: np.ndarray, lower: np.ndarray
) -> np.ndarray:
    """The weights moved so that every log's ±2σ coverage lies in :data:`COVERAGE_BAND`
    where the features allow: the per-log likelihood plus :data:`BAND_PENALTY` times the
    squared distance of each log's coverage (a smooth count) from the band, Nelder-Mead in
    log(w - lower) from ``weights``; every third sample."""
    logs = [(d.features.reshape(-1, len(weights))[::3] ** 2, d.error.ravel()[::3], o[::3])
            for d, o in zip(data, offsets)]  # fmt: skip
    logs = [(g, e, o) for g, e, o in logs if e.size]
    scale = np.fmax(weights - lower, 1e-12 * np.fmax(weights.max(), 1e-300))
    low, high = COVERAGE_BAND

    def objective(theta: np.ndarray) -> float:
        w = lower + scale * np.exp(theta)
        total = 0.0
        for g, e, o in logs:
            v = np.fmax(g @ w + o, 1e-300)
            s = np.sqrt(v)
            covered = np.mean(special.expit((2 * s - np.abs(e)) / (0.1 * s)))
            likelihood = np.mean(np.log(v) + e**2 / v)
            total += likelihood / len(logs)
            total += BAND_PENALTY * (max(0.0, low - covered) ** 2 + max(0.0, covered - high) ** 2)
        return total

    found = optimize.minimize(
        objective,
        np.zeros(len(weights)),
        method="Nelder-Mead",
        options={"maxiter": 3000, "xatol": 1e-3, "fatol": 1e-8},
    )
    return lower + scale * np.exp(found.x)


def calibrate_sigma(vehicle: Vehicle, logs: tuple[Signals, ...]) -> SigmaFit:
    """The reported-sigma model fitted on logs with reference loads, with the KF of
    ``vehicle`` (its guards and densities); a feature the logs never exercise keeps the
    file's coefficient. With two logs or more, each log's coverage is also measured with
    the model fitted on the others (``held_out``)."""
    data = [sigma_data(TwoStageKF(vehicle), signals) for signals in logs]
    held = np.array(vehicle.filter.sigma_model())
    fit = fit_sigma(data, held=held)
    if len(data) < 2:
        return fit
    held_out = []
    for k, left_out in enumerate(data):
        others = [d for j, d in enumerate(data) if j != k]
        held_out.append(scores([left_out], fit_sigma(others, held=held).coefficients)[0])
    return dataclasses.replace(fit, held_out=tuple(held_out))


def with_sigma(vehicle: Vehicle, coefficients: np.ndarray) -> Vehicle:
    """``vehicle`` with its ``[filter] sigma_*`` coefficients replaced."""
    named = {key: float(value) for key, value in zip(SIGMA_KEYS, coefficients, strict=True)}
    return vehicle.replace(filter=dataclasses.replace(vehicle.filter, **named))


#: Least ±2σ coverage a tuned file may promise a log it was not tuned on.
MIN_HELD_OUT_COVERAGE = 0.90


def coverage_warnings(what: str, coverages) -> list[str]:
    """A warning for each ``(log, coverage)`` below :data:`MIN_HELD_OUT_COVERAGE`, with the
    figure and what to do (``wheelload tune`` prints them)."""
    return [
        f"{what} is {100 * coverage:.1f} % on {name}, below "
        f"{100 * MIN_HELD_OUT_COVERAGE:.0f} %: the reported σ is calibrated on logs unlike "
        "it; tune on logs that include its kind of driving, or keep the input file's "
        "sigma_* keys"
        for name, coverage in coverages
        if coverage < MIN_HELD_OUT_COVERAGE
    ]
