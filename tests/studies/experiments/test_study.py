"""``wheelload study mhe-vs-kf`` end to end on the bundled plant log."""

import numpy as np
import pandas as pd

from wheelload.estimators import read_log
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.studies.cli import main
from wheelload.studies.metrics import pooled_metrics
from wheelload.studies.pipeline.example_log import example_log_path


def test_study_table_and_figure(tmp_path, capsys, vehicle, fixed_vehicle):
    out = tmp_path / "study"
    code = main(["study", "mhe-vs-kf", "--sweep", "equivalence", "--logs",
                 str(example_log_path()), "--horizons", "1", "5", "--out", str(out)])  # fmt: skip
    assert code == 0
    table = pd.read_csv(out.with_suffix(".csv"), index_col=0)
    assert out.with_suffix(".png").stat().st_size > 20_000
    assert "two-stage KF" in capsys.readouterr().out
    # Independent check of the KF row: the filter run directly on the same log.
    signals = read_log(example_log_path())
    direct = pooled_metrics(TwoStageKF(vehicle).run(signals).loads, signals.reference)
    assert np.isclose(table.loc["two-stage KF", "RMSE"], direct["RMSE"], rtol=1e-9)
    # Soft MHE without bounds and with the Kalman arrival cost is the KF with the file's mass
    # (the window has no payload filter; solver tolerance 1e-3 N on loads of ~4 kN: RMSE
    # equal to 0.1 N); bounded rows never go below 0 N.
    fixed = TwoStageKF(fixed_vehicle).run(signals).loads
    soft = table.loc[[name for name in table.index if name.endswith("(soft)")], "RMSE"]
    assert len(soft) == 2
    assert np.allclose(soft, pooled_metrics(fixed, signals.reference)["RMSE"], atol=0.1)
    bounded = table.loc[[name for name in table.index if "bounded" in name], "min load"]
    assert (bounded >= 0.0).all()
    # three filters; four MHE variants with the Kalman arrival and one with the steady
    # arrival, at two horizons
    assert len(table) == 3 + 5 * 2


def test_robust_sweep_on_a_faulted_plant_log(tmp_path, capsys, vehicle):
    out = tmp_path / "robust"
    code = main(["study", "mhe-vs-kf", "--logs", str(example_log_path()), "--quick",
                 "--horizon", "6", "--faults", "clean", "spikes", "--out", str(out)])  # fmt: skip
    assert code == 0
    table = pd.read_csv(out.with_suffix(".csv"), index_col=0)
    change = pd.read_csv(out.with_name("robust-vs-kf.csv"), index_col=0)
    assert list(table.columns[:2]) == ["clean", "spikes"]
    # Independent check: the KF run directly on the spiked log.
    from wheelload.studies.experiments.faults.sensor_faults import Fault, inject

    signals = read_log(example_log_path())
    direct = TwoStageKF(vehicle).run(inject(signals, Fault.SPIKES)).loads
    expected = pooled_metrics(direct, signals.reference)["RMSE"]
    assert np.isclose(table.loc["two-stage KF", "spikes"], expected, rtol=1e-9)
    assert (change.loc["two-stage KF"] == 0.0).all()
    # the Huber window rejects single-sample travel spikes the filter follows, even with its
    # innovation gate and fault monitor (measured 30.9 N against 47.8 N at N = 10)
    huber = [name for name in table.index if "Huber 0.5" in name][0]
    assert table.loc[huber, "spikes"] < 0.85 * table.loc["two-stage KF", "spikes"]
    assert table.loc[huber, "clean"] < 1.05 * table.loc["two-stage KF", "clean"]
    assert "change against the two-stage KF" in capsys.readouterr().out
