"""The two cached units of work of every study: simulate a scenario, score methods on it.

:func:`simulate_truth` runs the plant through the scenario runner
(:func:`wheelload.studies.drive.scenario_runner.run_scenario`) and keeps the clean
truth frame. :func:`run_trial` measures that frame with the sensor models at
noise scale ``s`` and seed (paper §IV-F: the noise is drawn afresh on one
simulated drive), builds each method through the registry from the
estimator's vehicle file (which a study may edit: ablation, mismatch) on the spec's
estimators' model (``wheelload study --model``: the file's or the paper's), the
family methods on the spec's vehicle model (``wheelload study --suspension``), and
scores it with the paper's metrics (eq. 26-34) over the evaluation window.
"""

from __future__ import annotations

import tempfile
import time
import tomllib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators import DEFAULT_MODEL, SuspensionModel
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models.vehicle.description import Vehicle, vehicle_from_dict
from wheelload.studies.drive.payload_schedule import PayloadSchedule
from wheelload.studies.drive.scenario_options import BeyondGrip, Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.sensors import MTI_1, NoiseScaling, measure, sensor_grade
from wheelload.studies.experiments.runs.cache import ResultCache
from wheelload.studies.experiments.runs.estimator_model import EstimatorModel, on_model
from wheelload.studies.metrics import wheel_metrics

TRUTH = "truth"
TRIAL = "trial"
KF_TRIALS = "kf-trials"
INTERNAL_RATE = 1000.0  # Hz, the plant's integration rate (a multiple of every output rate)


@dataclass(frozen=True, kw_only=True)
class TruthSpec:
    """A plant run: scenario, the plant's vehicle file (its text), lap share, seed, the log's
    output rate (the plant integrates at :data:`INTERNAL_RATE`, a multiple of it), and the
    payload the plant carries (the vehicle file does not know it)."""

    scenario: str
    vehicle_text: str
    shorten: float = 1.0
    seed: int = 0
    payload: PayloadSchedule | None = None
    output_rate: float = 100.0  # Hz
    beyond_grip: BeyondGrip | None = None  # the turns driven beyond the grip (Options)


@dataclass(frozen=True, kw_only=True)
class TrialSpec:
    """Methods scored on one measured copy of a plant run."""

    truth: TruthSpec
    vehicle_text: str  # the estimators' vehicle file (an edited copy in ablation / mismatch)
    methods: tuple[str, ...]
    noise: float = 1.0  # sensor noise scale s (paper §IV-F)
    scaling: NoiseScaling = NoiseScaling.ALL  # which sensor errors s multiplies
    sensors: str = MTI_1.name  # sensor grade (studies.drive.sensors.GRADES)
    seed: int = 0  # measurement seed
    window: tuple[float, float] | None = None  # scored samples, t in [start, end] s
    keep_estimates: bool = False  # keep the loads for figures
    suspension: SuspensionModel = DEFAULT_MODEL  # vehicle model of the family methods
    model: EstimatorModel = EstimatorModel.FULL  # the estimators' model (wheelload study --model)
    truth_key: str = ""  # cache key of ``truth``, set by the process that plans the jobs
    mass_properties_at: float | None = None  # s, keep the estimated mass properties then


@dataclass(frozen=True, kw_only=True, eq=False)
class TrialResult:
    """Per method: metric table (fl fr rl rr pooled × RMSE, RMSE %, P95, Max) or the error."""

    metrics: dict[str, pd.DataFrame]
    errors: dict[str, str]
    seconds_per_sample: dict[str, float]
    t: np.ndarray | None = None  # scored samples only, when estimates are kept
    s: np.ndarray | None = None  # distance along the road [m]
    reference: np.ndarray | None = None
    estimates: dict[str, np.ndarray] | None = None
    # per method estimating them: [mass, cg_x, cg_y, cg_height] and their std at
    # ``TrialSpec.mass_properties_at`` (:func:`mass_properties_at`)
    mass_properties: dict[str, np.ndarray] | None = None


def mass_properties_at(estimate, t: np.ndarray, time: float) -> np.ndarray | None:
    """``[mass, cg_x, cg_y, cg_height, their four std]`` of ``estimate`` at the last sample
    at or before ``time`` [s]; None for an estimator that does not estimate them (no
    ``mass_properties``); a missing std is NaN."""
    values = getattr(estimate, "mass_properties", None)
    if values is None:
        return None
    k = max(int(np.searchsorted(t, time, side="right")) - 1, 0)
    std = getattr(estimate, "mass_properties_std", None)
    spread = np.full(4, np.nan) if std is None else np.asarray(std, float)[k]
    return np.concatenate([np.asarray(values, float)[k], spread])


def simulate_truth(spec: TruthSpec, folder: Path) -> pd.DataFrame:
    """The clean truth frame of the plant run (``folder`` unused: no dependency)."""
    with tempfile.TemporaryDirectory() as temporary:
        path = Path(temporary) / "vehicle.toml"
        path.write_text(spec.vehicle_text, encoding="utf-8")
        options = Options(seed=spec.seed, shorten=spec.shorten, beyond_grip=spec.beyond_grip)
        result = run_scenario(
            spec.scenario,
            path,
            options=options,
            noise=0.0,
            output_rate=spec.output_rate,
            internal_rate=INTERNAL_RATE,
            payload=spec.payload,
        )
    return result.truth.frame


@lru_cache(maxsize=4)
def _truth(folder: str, key: str) -> pd.DataFrame:
    return ResultCache(folder=Path(folder)).load(key)


@lru_cache(maxsize=8)
def _vehicle(text: str, model: EstimatorModel) -> Vehicle:
    return on_model(vehicle_from_dict(tomllib.loads(text)), model)


def estimators_vehicle(spec: TrialSpec) -> Vehicle:
    """The vehicle the estimators of ``spec`` are built on: its file on its model."""
    return _vehicle(spec.vehicle_text, spec.model)


def measured(spec: TrialSpec, folder: Path) -> pd.DataFrame:
    """The measured log: the sensor models on the cached truth (run it first).

    The truth's key comes with the spec: a worker never hashes the code itself (its files
    may differ from those of the process that planned the run).
    """
    if not spec.truth_key:
        raise ValueError("TrialSpec.truth_key is not set: plan trials with common.trials()")
    truth = _truth(str(folder), spec.truth_key)
    rng = np.random.default_rng(np.random.SeedSequence([spec.seed, 1]))
    return measure(truth, spec.noise, rng, sensor_grade(spec.sensors), spec.scaling)


def run_trial(spec: TrialSpec, folder: Path) -> TrialResult:
    """Score every method of ``spec`` on its measured log; a failing method is recorded."""
    log = measured(spec, folder)
    # the plant's own log: its signs and units are right by construction (no wiring checks)
    signals = signals_from_frame(log, source=spec.truth.scenario, wiring_checks=False)
    t = signals.t
    mask = np.ones(t.size, bool)
    if spec.window is not None:
        mask = (t >= spec.window[0]) & (t <= spec.window[1])
        if not mask.any():
            raise ValueError(f"{spec.truth.scenario}: window {spec.window} holds no sample")
    vehicle = estimators_vehicle(spec)
    metrics, errors, seconds, estimates, masses = {}, {}, {}, {}, {}
    for name in spec.methods:
        try:
            estimator = build(name, vehicle, spec.suspension)
            start = time.perf_counter()
            estimate = estimator.run(signals)
            seconds[name] = (time.perf_counter() - start) / t.size
            metrics[name] = wheel_metrics(estimate.loads[mask], signals.reference[mask])
            if spec.keep_estimates:
                estimates[name] = estimate.loads[mask].astype(np.float32)
            if spec.mass_properties_at is not None:
                found = mass_properties_at(estimate, t, spec.mass_properties_at)
                if found is not None:
                    masses[name] = found
        except (ValueError, ArithmeticError, RuntimeError) as error:
            errors[name] = f"{type(error).__name__}: {error}".splitlines()[0]
    kept = masses if spec.mass_properties_at is not None else None
    if not spec.keep_estimates:
        return TrialResult(
            metrics=metrics, errors=errors, seconds_per_sample=seconds, mass_properties=kept
        )
    return TrialResult(
        metrics=metrics,
        errors=errors,
        seconds_per_sample=seconds,
        t=t[mask],
        s=log["s"].to_numpy()[mask],
        reference=signals.reference[mask],
        estimates=estimates,
        mass_properties=kept,
    )


@dataclass(frozen=True, kw_only=True)
class KfTrials:
    """Trials of the two-stage KF alone, filtered side by side (one unit of work)."""

    specs: tuple[TrialSpec, ...]  # same vehicle_text; methods == ("kf",)


def run_kf_trials(batch: KfTrials, folder: Path) -> list[TrialResult]:
    """:func:`run_trial` of each spec with the KF, the logs stepped side by side in C.

    The measured logs differ only in their noise draws, so they go through the
    generated library's batched step together
    (:func:`wheelload.estimators.codegen.batched.run_batched`); the loads equal the
    KF's ``run`` on each log to about 1e-12 relative.
    """
    from wheelload.estimators.codegen.batched import run_batched

    texts = {(spec.vehicle_text, spec.model) for spec in batch.specs}
    if len(texts) != 1 or any(spec.methods != ("kf",) for spec in batch.specs):
        raise ValueError("KfTrials: one vehicle file and model, and the method 'kf' only")
    logs, masks = [], []
    for spec in batch.specs:
        log = measured(spec, folder)
        signals = signals_from_frame(log, source=spec.truth.scenario, wiring_checks=False)
        mask = np.ones(signals.t.size, bool)
        if spec.window is not None:
            mask = (signals.t >= spec.window[0]) & (signals.t <= spec.window[1])
            if not mask.any():
                raise ValueError(f"{spec.truth.scenario}: window {spec.window} holds no sample")
        logs.append(signals)
        masks.append(mask)
    estimator = build("kf", estimators_vehicle(batch.specs[0]))
    with tempfile.TemporaryDirectory() as temporary:
        path = Path(temporary) / "vehicle.toml"
        path.write_text(batch.specs[0].vehicle_text, encoding="utf-8")
        start = time.perf_counter()
        estimates = run_batched(estimator, path, logs)
        seconds = (time.perf_counter() - start) / sum(log.t.size for log in logs)
    results = []
    for signals, mask, estimate in zip(logs, masks, estimates, strict=True):
        try:
            metrics = {"kf": wheel_metrics(estimate.loads[mask], signals.reference[mask])}
            errors = {}
        except (ValueError, ArithmeticError) as error:
            metrics, errors = {}, {"kf": f"{type(error).__name__}: {error}".splitlines()[0]}
        results.append(
            TrialResult(metrics=metrics, errors=errors, seconds_per_sample={"kf": seconds})
        )
    return results
