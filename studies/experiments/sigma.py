"""Study ``sigma``: calibration of the KF's reported σ and its table.

The reported-σ model (``estimators/kf/reported_std.py``) is fitted
(``estimators/identification/sigma_fit.py``: Gaussian likelihood of the errors, then one
scale to 95 % ±2σ coverage) on both bundled vehicles' standard scenarios, clean and with
sensor noise s = 1, measurement seeds :data:`FIT_SEEDS`, every scenario but
:data:`HELD_OUT_SCENARIOS`; it is reported on all of them (seeds 0-4). Per scenario: ±2σ
coverage and the Pearson r of σ and ``|error|`` with the filter's own σ (sqrt P), the
coefficients the vehicle file gives (the code defaults where it gives none) and this
run's fit; each with every sensor and IMU-only (travel columns dropped, true file); then
every ±20 % file of the ``mismatch`` study (the plant keeps the true file), whose σ should
rise with the error.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.identification.sigma_fit import SigmaData, fit_sigma, scores, sigma_data
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models.inputs import TRAVEL, TRAVEL_RATE
from wheelload.models.vehicle.description import SIGMA_KEYS, vehicle_from_dict
from wheelload.studies.drive.scenarios import SCENARIOS
from wheelload.studies.experiments.mismatch import mismatch_variants
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.cache import cache_key
from wheelload.studies.experiments.runs.common import Section, simulate, truth_spec
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.runner import Job
from wheelload.studies.experiments.runs.units import (
    TRUTH,
    TrialSpec,
    estimators_vehicle,
    measured,
)
from wheelload.studies.experiments.vehicles import vehicle_files

SIGMA_DATA = "sigma-data"
SIGMA_DATA_IMU_ONLY = "sigma-data-imu-only"
#: Sensor sets: every channel, or IMU-only (travel columns dropped; the true file only).
SENSORS = ("all", "IMU only")
NO_TRAVEL_KEYS = tuple(key for key in SIGMA_KEYS if key.startswith("sigma_no_travel"))
SEEDS = (0, 1, 2, 3, 4)
FIT_SEEDS = (0, 1, 2)
HELD_OUT_SCENARIOS = ("nordschleife",)
STRIDE = 2  # every second sample is kept (the errors are correlated over many samples)
#: Measurement conditions: (label, noise scale, seeds).
CONDITIONS = (("clean", 0.0, (0,)), ("sensor errors", 1.0, SEEDS))


def sigma_trial(spec: TrialSpec, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """Errors and σ features of the KF on one measured log (a unit of work; arrays, as the
    cache holds them)."""
    return _trial(measured(spec, folder), spec)


def sigma_trial_imu_only(spec: TrialSpec, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sigma_trial` on the log without its travel and travel-rate columns."""
    log = measured(spec, folder)
    return _trial(log.drop(columns=[c for c in (*TRAVEL, *TRAVEL_RATE) if c in log]), spec)


def _trial(log: pd.DataFrame, spec: TrialSpec) -> tuple[np.ndarray, np.ndarray]:
    signals = signals_from_frame(log, source=spec.truth.scenario, wiring_checks=False)
    kf = build("kf", estimators_vehicle(spec))
    data = sigma_data(kf, signals).thinned(STRIDE)
    return data.error, data.features


@dataclass(frozen=True, kw_only=True)
class Case:
    vehicle: str
    scenario: str
    condition: str
    file: str  # "true" or a mismatch variant's label
    sensors: str  # one of SENSORS
    seed: int
    coefficients: tuple[float, ...]  # the estimators' file's own


def _plan(context: Context) -> tuple[list[Case], list[TrialSpec]]:
    cases, specs = [], []
    for path in vehicle_files(context.settings.vehicles_folder):
        text = path.read_text(encoding="utf-8")
        variants = [(v.label, v.apply(text)) for v in mismatch_variants(text)]
        for scenario in SCENARIOS:
            truth = truth_spec(context, scenario, vehicle_text=text)
            for label, file_text in variants:
                coefficients = vehicle_from_dict(tomllib.loads(file_text)).filter.sigma_model()
                for condition, noise, seeds in CONDITIONS:
                    # the wrong files on one noise draw each, with every sensor
                    for seed in seeds if label == "true" else seeds[:1]:
                        for sensors in SENSORS if label == "true" else SENSORS[:1]:
                            cases.append(Case(vehicle=path.stem, scenario=scenario,
                                              condition=condition, file=label,
                                              sensors=sensors, seed=seed,
                                              coefficients=coefficients))  # fmt: skip
                            specs.append(TrialSpec(truth=truth, vehicle_text=file_text,
                                                   methods=("kf",), noise=noise,
                                                   seed=seed))  # fmt: skip
    return cases, specs


def _row(group: list[SigmaData], coefficients: dict[str, np.ndarray]) -> dict[str, float]:
    group = [d for d in group if d.error.size]
    if not group:  # no settled sample (a --quick segment shorter than the settling time)
        return {"RMSE [N]": float("nan")} | {
            f"{label} {score}": float("nan")
            for label in coefficients
            for score in ("±2σ [%]", "r", "mean σ [N]")
        }
    error = np.concatenate([d.error.ravel() for d in group])
    row = {"RMSE [N]": float(np.sqrt(np.mean(error**2)))}
    for label, c in coefficients.items():
        coverage, r = scores(group, c)
        row[f"{label} ±2σ [%]"] = 100.0 * coverage
        row[f"{label} r"] = r
        row[f"{label} mean σ [N]"] = float(
            np.mean(np.concatenate([d.std(c).ravel() for d in group]))
        )
    return row


def run(context: Context) -> Section:
    cases, specs = _plan(context)
    simulate(context, list(dict.fromkeys(spec.truth for spec in specs)))
    units = {SENSORS[0]: (SIGMA_DATA, sigma_trial),
             SENSORS[1]: (SIGMA_DATA_IMU_ONLY, sigma_trial_imu_only)}  # fmt: skip
    jobs = [
        Job(kind=units[c.sensors][0], function=units[c.sensors][1],
            spec=TrialSpec(truth=s.truth, vehicle_text=s.vehicle_text, methods=s.methods,
                           noise=s.noise, seed=s.seed, truth_key=cache_key(TRUTH, s.truth),
                           model=context.settings.model))
        for c, s in zip(cases, specs)
    ]  # fmt: skip
    data = [SigmaData(error=e, features=g) for e, g in context.runner.run(jobs, "sigma")]
    held = [c.scenario in HELD_OUT_SCENARIOS or c.seed not in FIT_SEEDS for c in cases]
    # Two stages: every coefficient on the logs with all sensors (the no-travel features are
    # 0 there), then the no-travel ones on the IMU-only logs beside the others held.
    fit_set = [(c, d) for c, d, h in zip(cases, data, held) if c.file == "true" and not h]
    fit = fit_sigma([d for c, d in fit_set if c.sensors == SENSORS[0]])
    fit = fit_sigma([d for c, d in fit_set if c.sensors == SENSORS[1]], held=fit.coefficients,
                    free=NO_TRAVEL_KEYS)  # fmt: skip
    own = np.eye(len(SIGMA_KEYS))[SIGMA_KEYS.index("sigma_covariance")]

    def table(key, keep) -> pd.DataFrame:
        groups: dict[tuple, list[tuple[Case, SigmaData]]] = {}
        for case, d in zip(cases, data):
            if keep(case):
                groups.setdefault(key(case), []).append((case, d))
        rows = {}
        for name, members in groups.items():
            first = members[0][0]
            coefficients = {"sqrt P": own, "file": np.array(first.coefficients),
                            "fit": fit.coefficients}  # fmt: skip
            rows[name] = _row([d for _, d in members], coefficients)
        return pd.DataFrame(rows).T

    per_scenario = table(lambda c: (c.vehicle, c.scenario, c.sensors, c.condition),
                         lambda c: c.file == "true")  # fmt: skip
    per_scenario.index.names = ["vehicle", "scenario", "sensors", "condition"]
    per_scenario.insert(
        0,
        "fit on",
        [
            "no" if s in HELD_OUT_SCENARIOS else "seeds 0-2"
            for s in per_scenario.index.get_level_values("scenario")
        ],  # fmt: skip
    )
    per_file = table(lambda c: (c.vehicle, c.file, c.condition),
                     lambda c: c.seed == 0 and c.sensors == SENSORS[0])  # fmt: skip
    per_file.index.names = ["vehicle", "file", "condition"]
    mean_sigma = per_file["file mean σ [N]"]
    true_sigma = {(v, cond): mean_sigma[(v, "true", cond)] for v, _, cond in per_file.index}
    per_file["file σ / true file's σ"] = [
        mean_sigma[i] / true_sigma[(i[0], i[2])] for i in per_file.index
    ]
    pooled = {}
    for label, keep in (("fit set", lambda c, h: not h), ("held out", lambda c, h: h),
                        ("all", lambda c, h: True)):  # fmt: skip
        for sensors in SENSORS:
            group = [d for c, d, h in zip(cases, data, held)
                     if c.file == "true" and c.sensors == sensors and keep(c, h)]  # fmt: skip
            pooled[f"{label}, {sensors}"] = _row(group, {"sqrt P": own, "fit": fit.coefficients})
    pooled_table = pd.DataFrame(pooled).T.rename_axis("logs")
    coefficients = pd.DataFrame({"fit": fit.coefficients}, index=list(SIGMA_KEYS))
    context.outputs.write_text("sigma_table.csv", per_scenario.to_csv(float_format="%.4g"))
    context.outputs.write_text("sigma_mismatch.csv", per_file.to_csv(float_format="%.4g"))
    context.outputs.write_text("sigma_coefficients.csv", coefficients.to_csv(float_format="%.6g"))
    shown = ["RMSE [N]", "sqrt P ±2σ [%]", "sqrt P r", "file ±2σ [%]", "file r",
             "fit ±2σ [%]", "fit r", "fit mean σ [N]"]  # fmt: skip
    body = "\n\n".join(
        [
            "## The reported σ: ±2σ coverage and correlation with |error| per scenario",
            "KF on the bundled vehicles, clean and with sensor noise s = 1 (seeds 0-4). "
            "`sqrt P`: the filter's own σ; `file`: the coefficients of the vehicle file (the "
            "code defaults where it gives none); `fit`: this run's calibration, fitted on "
            f"seeds {', '.join(map(str, FIT_SEEDS))} of every scenario but "
            f"{', '.join(HELD_OUT_SCENARIOS)} (clean runs count as seed 0).",
            "Coefficients of this fit (vehicle file `[filter]` keys): "
            + ", ".join(f"`{k} = {v:.4g}`" for k, v in zip(SIGMA_KEYS, fit.coefficients)),
            markdown(per_scenario[["fit on", *shown]], digits=2),
            "### Pooled",
            markdown(pooled_table, digits=3),
            "### With a wrong vehicle file (±20 %, the plant keeps the true one; seed 0)",
            markdown(per_file[[*shown, "file σ / true file's σ"]], digits=2),
        ]
    )
    return Section(title="Sigma", markdown=body)
