"""``wheelload study sensor-errors --quick``: the table, its verdict columns, a row checked
against a direct run, and ``simulate --sensors``."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.cli import main
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.sensors import measure, sensor_grade
from wheelload.studies.experiments.runs.common import ISO_DLC_WINDOW
from wheelload.studies.experiments.sensor_errors import (
    QUICK_RATES,
    QUICK_SCENARIOS,
    TERMS,
    ablated,
    term_table,
)
from wheelload.studies.metrics import wheel_metrics

pytestmark = pytest.mark.heavy(10)  # seconds (tests/conftest.py)


def test_the_quick_table_holds_every_row_and_matches_a_direct_run(tmp_path, capsys):
    out = tmp_path / "errors"
    code = main(["study", "sensor-errors", "--quick", "--out", str(out), "--no-progress"])
    assert code == 0
    capsys.readouterr()
    trials = pd.read_csv(out / "sensor_errors_trials.csv")
    table = pd.read_csv(out / "sensor_errors_table.csv", index_col=[0, 1, 2, 3])
    # 1 vehicle x 2 scenarios x 2 rates x 3 grades; the noisy grades at 2 seeds
    assert len(table) == len(QUICK_SCENARIOS) * len(QUICK_RATES) * 3
    assert len(trials) == len(QUICK_SCENARIOS) * len(QUICK_RATES) * (1 + 2 + 2)
    methods = ["kf", "C", "D", *(f"kf -{t}" for t in TERMS)]
    assert np.isfinite(table[methods].to_numpy()).all()
    assert set(table["KF best or within 5 %"]) <= {"yes", "no"}
    # Independent check of one line: the consumer grade at 500 Hz, seed 1, lane change:
    # the plant run, the sensor model, the registry's KF with and without body inertia,
    # the paper's metrics over the ISO window; equal to the CSV's printed digits.
    path = example_vehicle_path()
    truth = run_scenario("iso-dlc", path, options=Options(), noise=0.0, output_rate=500.0)
    rng = np.random.default_rng(np.random.SeedSequence([1, 1]))
    log = measure(truth.truth.frame, 1.0, rng, sensor_grade("consumer-mems"))
    signals = signals_from_frame(log, wiring_checks=False)
    mask = (signals.t >= ISO_DLC_WINDOW[0]) & (signals.t <= ISO_DLC_WINDOW[1])
    line = trials[(trials.scenario == "iso-dlc") & (trials.grade == "consumer-mems")
                  & (trials.rate == 500.0) & (trials.seed == 1)].iloc[0]  # fmt: skip
    text = path.read_text(encoding="utf-8")
    import tomllib

    from wheelload.models.vehicle.description import vehicle_from_dict

    for column, vehicle in (
        ("kf", load_vehicle(path)),
        ("kf -body_inertia", vehicle_from_dict(tomllib.loads(ablated(text, "body_inertia")))),
    ):
        loads = build("kf", vehicle).run(signals).loads
        direct = wheel_metrics(loads[mask], signals.reference[mask]).loc["pooled", "RMSE"]
        assert line[column] == pytest.approx(direct, rel=1e-9)
    # the term table: a change per grade and rate, and the verdict
    terms = term_table(trials)
    assert list(terms.index) == list(TERMS)
    assert terms.shape[1] == 3 * len(QUICK_RATES) + 2


def test_simulate_writes_the_chosen_grade(tmp_path, capsys):
    clean, mems = tmp_path / "clean.csv", tmp_path / "mems.csv"
    assert main(["simulate", "standstill", "--out", str(clean), "--sensors", "clean"]) == 0
    assert main(["simulate", "standstill", "--out", str(mems), "--sensors", "consumer-mems"]) == 0
    capsys.readouterr()
    a, b = pd.read_csv(clean), pd.read_csv(mems)
    # the same drive (seed 0): the consumer grade's vx carries 0.05 m/s of white noise
    assert (b["vx"] - a["vx"]).std() == pytest.approx(0.05, rel=0.15)  # 500 samples: ~3 %
    np.testing.assert_allclose(b[["d_fl"]].to_numpy() / 0.1e-3,
                               np.round(b[["d_fl"]].to_numpy() / 0.1e-3), atol=1e-6)  # fmt: skip
    with pytest.raises(SystemExit):
        main(["simulate", "standstill", "--out", str(tmp_path / "x.csv"), "--sensors", "mems"])
