"""Ablation of the model terms beyond the paper (issue 9): each term on and off.

For each vehicle and scenario the plant is simulated once, measured with the
sensor models (IMU, travel sensors, hub accelerometers) and filtered by the
two-stage KF with the vehicle file's ``[model]`` switches set per
configuration: the paper's model (every term off), each term alone, every
term, and every term but one. Scores are the pooled RMSE and Max over the
four wheels (Siegloff & Choi eq. 31-34) against the plant's reference loads.

Example
-------
>>> table = ablation([example_vehicle_path()], ["bounce-sweep"], Options())
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import ModelTerms, Vehicle, example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.experiments.equilibrium_residuals import paper_model, with_terms
from wheelload.studies.metrics import pooled_metrics

TERMS = tuple(field.name for field in dataclasses.fields(ModelTerms))
PAPER = "paper"
ALL = "all"


def bundled_vehicles() -> list[Path]:
    """The bundled sports car and SUV."""
    sports = example_vehicle_path()
    return [sports, sports.with_name("suv.toml")]


def label_groups() -> dict[str, list[str]]:
    """The configurations shown side by side: each term alone, every term but one."""
    return {
        "each term alone": [PAPER, *(f"+{term}" for term in TERMS), ALL],
        "every term but one": [ALL, *(f"-{term}" for term in TERMS)],
    }


def configurations(vehicle: Vehicle) -> dict[str, Vehicle]:
    """Name -> vehicle with its switches: paper, +term, all, -term."""
    paper = paper_model(vehicle)
    every = with_terms(paper, **dict.fromkeys(TERMS, True))
    result = {PAPER: paper}
    result.update({f"+{term}": with_terms(paper, **{term: True}) for term in TERMS})
    result[ALL] = every
    result.update({f"-{term}": with_terms(every, **{term: False}) for term in TERMS})
    return result


def ablation(
    vehicle_paths: Sequence[str | Path],
    scenarios: Sequence[str],
    options: Options,
    noise: float = 1.0,
    progress=None,
    allow_unusual: bool = False,
) -> pd.DataFrame:
    """Long table: vehicle, scenario, configuration, RMSE and Max [N]."""
    rows = []
    for path in vehicle_paths:
        vehicle = load_vehicle(path, allow_unusual=allow_unusual)
        for name in scenarios:
            result = run_scenario(
                name, path, options=options, noise=noise, allow_unusual=allow_unusual
            )
            signals = signals_from_frame(result.log, source=f"{vehicle.name}/{name}")
            for label, variant in configurations(vehicle).items():
                estimate = build("kf", variant).run(signals)
                metrics = pooled_metrics(estimate.loads, signals.reference)
                rows.append(
                    {"vehicle": vehicle.name, "scenario": name, "configuration": label,
                     "rmse": metrics["RMSE"], "max": metrics["Max"]}
                )  # fmt: skip
            if progress is not None:
                progress(f"{vehicle.name} {name}: {len(signals)} samples")
    return pd.DataFrame(rows)


def wide_table(table: pd.DataFrame, vehicle: str, labels: Sequence[str]) -> pd.DataFrame:
    """Scenarios x configurations of one vehicle, cells 'RMSE / Max' in N."""
    part = table[table["vehicle"] == vehicle]
    cells = part.assign(
        cell=[f"{r:.0f} / {m:.0f}" for r, m in zip(part["rmse"], part["max"], strict=True)]
    )
    wide = cells.pivot(index="scenario", columns="configuration", values="cell")
    order = list(dict.fromkeys(part["scenario"]))
    return wide.loc[order, [label for label in labels if label in wide.columns]]
