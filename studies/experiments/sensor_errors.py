"""Study ``sensor-errors``: the KF, its parts and its model terms under real sensor errors.

Every scenario of :data:`SCENARIOS` is simulated once per bundled vehicle and output
rate (:data:`RATES`; the plant integrates at 1 kHz), then measured with each sensor
grade (:data:`~wheelload.studies.drive.sensors.GRADES`: noise-free, MTi-1 class, consumer
MEMS) and seeds 0-4 (the noise-free grade once). Scored per row (vehicle, scenario,
grade, rate), as the pooled RMSE over the four wheels (Siegloff & Choi eq. 31-34)
averaged over the seeds: the two-stage KF, quasi-static C and suspension-only D, and
the KF with each model term of the vehicle file's ``[model]`` switched off in turn
(the mechanism of :mod:`~wheelload.studies.experiments.model_terms_ablation`).

Columns: whether the KF is first of kf, C, D or within :data:`WITHIN` of the best;
per term and (grade, rate), the KF's RMSE with the term against without it, the
geometric mean over scenarios and vehicles: a term *helps or is neutral* when switching
it on costs at most :data:`NEUTRAL` at every grade and rate; beside it, the rows
(vehicle, scenario, grade, rate) where it costs more.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from wheelload.models import ModelTerms
from wheelload.studies.drive.scenario_names import MANOEUVRES
from wheelload.studies.drive.sensors import GRADES
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import (
    Section,
    trials,
    truth_spec,
    window,
)
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialResult, TrialSpec
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant
from wheelload.studies.experiments.vehicles import vehicle_files

#: The manoeuvres but stop-and-go.
SCENARIOS = tuple(name for name in MANOEUVRES if name != "stop-and-go")
QUICK_SCENARIOS = ("iso-dlc", "standstill")
QUICK_VEHICLE = "sports_car"
RATES = (100.0, 500.0, 1000.0)  # Hz, output rate of the logs
QUICK_RATES = (100.0, 500.0)
SEEDS = (0, 1, 2, 3, 4)
QUICK_SEEDS = (0, 1)
TERMS = tuple(field.name for field in dataclasses.fields(ModelTerms))
FAMILY = ("C", "D")
WITHIN = 0.05  # the KF within 5 % of the best of kf, C, D
NEUTRAL = 0.02  # a term costs at most 2 %


@dataclasses.dataclass(frozen=True, kw_only=True)
class Row:
    """One measured case: which vehicle, scenario, grade, rate and seed."""

    vehicle: str
    scenario: str
    grade: str
    rate: float
    seed: int


def ablated(text: str, term: str) -> str:
    """The vehicle file ``text`` with model term ``term`` switched off."""
    return Variant(label=f"-{term}", edits=(Edit(table="model", key=term, value=False),)).apply(
        text
    )


def plan(context: Context) -> list[tuple[Row, TrialSpec]]:
    """Every measured case and its spec (the estimators' file: the vehicle's own)."""
    quick = context.settings.quick
    paths = vehicle_files(context.settings.vehicles_folder)
    if quick:
        paths = [path for path in paths if path.stem == QUICK_VEHICLE]
    cases = []
    for path in paths:
        text = path.read_text(encoding="utf-8")
        for scenario in QUICK_SCENARIOS if quick else SCENARIOS:
            for rate in QUICK_RATES if quick else RATES:
                truth = dataclasses.replace(
                    truth_spec(context, scenario, vehicle_text=text), output_rate=rate
                )
                for grade in GRADES:
                    seeds = (0,) if grade == "clean" else QUICK_SEEDS if quick else SEEDS
                    for seed in seeds:
                        row = Row(vehicle=path.stem, scenario=scenario, grade=grade, rate=rate,
                                  seed=seed)  # fmt: skip
                        spec = TrialSpec(truth=truth, vehicle_text=text, methods=("kf",),
                                         sensors=grade, seed=seed,
                                         window=window(scenario))  # fmt: skip
                        cases.append((row, spec))
    return cases


def _rmse(result: TrialResult, name: str) -> float:
    """The pooled RMSE of method ``name``, NaN where it failed."""
    if name not in result.metrics:
        return float("nan")
    return float(result.metrics[name].loc["pooled", "RMSE"])


def long_table(context: Context) -> pd.DataFrame:
    """One line per case and method: the pooled RMSE [N]."""
    cases = plan(context)
    rows = [dataclasses.asdict(row) for row, _ in cases]
    columns: dict[str, list[float]] = {}
    family = [dataclasses.replace(spec, methods=FAMILY) for _, spec in cases]
    results = trials(context, family, "sensor-errors C, D")
    for name in FAMILY:
        columns[name] = [_rmse(result, name) for result in results]
    for label, edit in (("kf", None), *((f"kf -{t}", t) for t in TERMS)):
        specs = [spec if edit is None else dataclasses.replace(
            spec, vehicle_text=ablated(spec.vehicle_text, edit)) for _, spec in cases]  # fmt: skip
        columns[label] = [_rmse(r, "kf") for r in trials(context, specs, f"sensor-errors {label}")]
    frame = pd.DataFrame(rows)
    for name, values in columns.items():
        frame[name] = values
    return frame


def row_table(frame: pd.DataFrame) -> pd.DataFrame:
    """Per vehicle, scenario, grade and rate: mean RMSE over the seeds and the KF's rank."""
    keys = ["vehicle", "scenario", "grade", "rate"]
    methods = ["kf", *FAMILY, *(f"kf -{t}" for t in TERMS)]
    table = frame.groupby(keys, sort=False)[methods].mean()
    best = table[["kf", *FAMILY]].min(axis=1)
    table["KF best or within 5 %"] = np.where(table["kf"] <= (1.0 + WITHIN) * best, "yes", "no")
    return table


def term_table(frame: pd.DataFrame) -> pd.DataFrame:
    """Per term and (grade, rate): the KF's RMSE with the term against without it [%, > 0:
    the term costs], the geometric mean of the rows' ratios (every scenario and vehicle
    weighs the same); the rows where it costs more than :data:`NEUTRAL`; the verdict."""
    rows = row_table(frame)
    cells, costly = {}, {}
    for term in TERMS:
        ratio = np.log(rows["kf"] / rows[f"kf -{term}"])
        change = 100.0 * np.expm1(ratio.groupby(level=["grade", "rate"], sort=False).mean())
        cells[term] = {f"{g} {r:.0f} Hz": c for (g, r), c in change.items()}
        costly[term] = int((ratio > np.log1p(NEUTRAL)).sum())
    table = pd.DataFrame(cells).T
    verdict = (table.to_numpy() <= 100.0 * NEUTRAL).all(axis=1)
    table[f"rows costing > {100 * NEUTRAL:.0f} %"] = [f"{costly[t]} of {len(rows)}" for t in TERMS]
    table["helps or neutral everywhere"] = np.where(verdict, "yes", "no")
    table.index.name = "term"
    return table


def run(context: Context) -> Section:
    frame = long_table(context)
    rows = row_table(frame)
    terms = term_table(frame)
    context.outputs.write_text("sensor_errors_trials.csv", frame.to_csv(index=False))
    context.outputs.write_text("sensor_errors_table.csv", rows.to_csv(float_format="%.3f"))
    context.outputs.write_text("sensor_errors_terms.csv", terms.to_csv(float_format="%.3f"))
    first = int((rows["KF best or within 5 %"] == "yes").sum())
    body = "\n\n".join(
        [
            "## Sensor errors: grades x rates x scenarios x vehicles, pooled RMSE [N]",
            "Mean over seeds " + ", ".join(str(s) for s in sorted(set(frame["seed"])))
            + " (the noise-free grade: one run). `kf -TERM`: the KF with that model term "
            "switched off in the vehicle file.",
            markdown(rows.reset_index().set_index(["vehicle", "scenario"]), digits=1),
            f"The KF is first of kf, C, D or within 5 % of the best on {first} of "
            f"{len(rows)} rows.",
            "## Model terms: the KF's RMSE with the term against without it [%]",
            "Geometric mean over every scenario and vehicle, per grade and output rate; > 0: "
            f"the term costs. A term helps or is neutral where it costs at most "
            f"{100 * NEUTRAL:.0f} %; the rows where it costs more are counted beside.",
            markdown(terms, digits=1),
        ]
    )  # fmt: skip
    return Section(title="Sensor errors", markdown=body)
