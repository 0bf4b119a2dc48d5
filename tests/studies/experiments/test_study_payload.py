"""``wheelload study payload --quick``: its table, against a direct run of the plain scenario."""

from __future__ import annotations

import tomllib

import numpy as np
import pandas as pd

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import example_vehicle_path
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.cli import main
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.experiments.payload import EXACT, METHODS, NOT_ESTIMATED
from wheelload.studies.experiments.runs.common import ISO_DLC_WINDOW
from wheelload.studies.metrics import wheel_metrics


def test_quick_payload_study_table_and_its_exact_file_row(tmp_path):
    out = tmp_path / "payload"
    assert main(["study", "payload", "--quick", "--out", str(out), "--no-progress"]) == 0
    table = pd.read_csv(out / "payload_table.csv")
    assert "## Payload the vehicle file does not know" in (out / "payload.md").read_text()
    assert len(table) == 6  # iso-dlc, standstill: exact + 150 kg; stop-and-go: exact + passenger
    numbers = [f"{m} {c}" for m in METHODS for c in ("RMSE [N]", "ratio")]
    assert np.isfinite(table[numbers + ["mass [kg]", "CG x [mm]"]].to_numpy()).all()
    exact = table[table["payload"] == EXACT]
    np.testing.assert_allclose(exact[[f"{m} ratio" for m in METHODS]], 1.0)
    # Estimated mass properties: numbers where a method reports them, else the cell says so.
    if "estimated mass, CG x" in table:
        assert (table["estimated mass, CG x"] == NOT_ESTIMATED).all()
    # The payload-0 iso-dlc row is the plain scenario: the scenario runner's own log (noise
    # 1, seed 0), the KF from the registry, the paper's metrics over 5-12 s (CSV: 3 decimals).
    path = example_vehicle_path()
    log = run_scenario("iso-dlc", path).log
    signals = signals_from_frame(log)
    mask = (signals.t >= ISO_DLC_WINDOW[0]) & (signals.t <= ISO_DLC_WINDOW[1])
    vehicle = vehicle_from_dict(tomllib.loads(path.read_text()))
    row = exact[exact["scenario"] == "iso-dlc"].iloc[0]
    for name in METHODS:
        loads = build(name, vehicle).run(signals).loads
        direct = wheel_metrics(loads[mask], signals.reference[mask]).loc["pooled", "RMSE"]
        assert abs(row[f"{name} RMSE [N]"] - direct) < 1e-3
    # The loaded rows are worse for the methods that trust the file's static loads.
    loaded = table[(table["scenario"] == "iso-dlc") & (table["payload"] != EXACT)].iloc[0]
    assert loaded["C ratio"] > 2.0
    assert loaded["mass [kg]"] == float(row["mass [kg]"]) + 150.0
