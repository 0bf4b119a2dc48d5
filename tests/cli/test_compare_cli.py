"""``wheelload methods``, ``estimate --method`` and ``compare`` on real files."""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.registry import methods, tyre_methods
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.metrics import wheel_metrics
from wheelload.studies.pipeline.example_log import example_log_path

VEHICLE = str(example_vehicle_path())


def test_methods_lists_every_registered_name(capsys):
    assert main(["methods"]) == 0
    out = capsys.readouterr().out
    for name, info in (*methods().items(), *tyre_methods().items()):
        assert f"{name} " in out and info.reference in out


def test_estimate_with_a_method_without_sigma(tmp_path, capsys):
    out = tmp_path / "c.csv"
    assert main(["estimate", "--example", "--method", "C", "--out", str(out)]) == 0
    assert "n/a" in capsys.readouterr().out
    frame = pd.read_csv(out)
    assert "fz_std_fl" not in frame.columns and np.isfinite(frame.to_numpy()).all()


def test_estimate_unknown_method_is_one_line(capsys):
    assert main(["estimate", "--example", "--method", "kalman"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "unknown method 'kalman'" in err and "E+C" in err


def test_compare_prints_the_paper_table_and_writes_figures(tmp_path, capsys):
    log = tmp_path / "drive.csv"
    log.write_bytes(example_log_path().read_bytes())
    table = tmp_path / "table.csv"
    args = ["compare", str(log), "--vehicle", VEHICLE, "--methods", "kf,C,D,F", "--repeat", "1"]
    assert main([*args, "--figures", str(tmp_path), "--csv", str(table), "--start", "2"]) == 0
    out = capsys.readouterr().out
    for label in ("RMSE [N]", "RMSE [%]", "P95 [N]", "MAX [N]", "time per sample"):
        assert label in out
    frame = pd.read_csv(table)
    assert list(frame["method"].unique()) == ["kf", "C", "D", "F"]
    # The table's numbers are the metrics of the method's estimate over the window t >= 2 s.
    from wheelload.estimators import read_log
    from wheelload.estimators.registry import build
    from wheelload.models import load_vehicle

    signals = read_log(log)
    keep = signals.t >= 2
    loads = build("C", load_vehicle(example_vehicle_path())).run(signals).loads
    expected = wheel_metrics(loads[keep], signals.reference[keep])
    row = frame[(frame.method == "C") & (frame.wheel == "pooled")].iloc[0]
    assert row["RMSE"] == pytest.approx(expected.loc["pooled", "RMSE"], rel=1e-12)
    for wheel in ("fl", "fr", "rl", "rr"):
        assert (tmp_path / f"drive_compare_{wheel}.png").stat().st_size > 20_000
    # Existing outputs are not overwritten without --force.
    assert main([*args, "--csv", str(table)]) == 2
    assert "give --force" in capsys.readouterr().err
    assert main([*args, "--csv", str(table), "--force"]) == 0


def test_compare_refuses_a_log_without_reference(tmp_path, capsys):
    frame = pd.read_csv(example_log_path())
    log = tmp_path / "plain.csv"
    frame.drop(columns=["fz_fl", "fz_fr", "fz_rl", "fz_rr"]).to_csv(log, index=False)
    assert main(["compare", str(log), "--vehicle", VEHICLE, "--methods", "C"]) == 2
    assert "no reference loads" in capsys.readouterr().err


def test_compare_rejects_an_empty_window(tmp_path, capsys):
    code = main(["compare", str(example_log_path()), "--vehicle", VEHICLE, "--methods", "C",
                 "--start", "100"])  # fmt: skip
    assert code == 2
    assert "holds no sample" in capsys.readouterr().err


@pytest.mark.parametrize("choice", ["full", "paper"])
def test_compare_and_estimate_take_the_family_model(tmp_path, capsys, choice):
    from wheelload.estimators import read_log
    from wheelload.estimators.protocol import SuspensionModel
    from wheelload.estimators.registry import build
    from wheelload.models import load_vehicle

    log = tmp_path / "drive.csv"
    log.write_bytes(example_log_path().read_bytes())
    table = tmp_path / "table.csv"
    args = ["compare", str(log), "--vehicle", VEHICLE, "--methods", "kf,D", "--repeat", "1"]
    assert main([*args, "--csv", str(table), "--suspension", choice]) == 0
    assert f"family methods on the {choice} vehicle model" in capsys.readouterr().out
    signals = read_log(log)
    vehicle = load_vehicle(example_vehicle_path())
    loads = build("D", vehicle, SuspensionModel.parse(choice)).run(signals).loads
    frame = pd.read_csv(table)
    row = frame[(frame.method == "D") & (frame.wheel == "pooled")].iloc[0]
    expected = wheel_metrics(loads, signals.reference).loc["pooled", "RMSE"]
    assert row["RMSE"] == pytest.approx(expected, rel=1e-12)
    out = tmp_path / "d.csv"
    command = ["estimate", str(log), "--vehicle", VEHICLE, "--method", "D", "--out", str(out)]
    assert main([*command, "--suspension", choice]) == 0
    assert f"{choice} vehicle model (--suspension)" in capsys.readouterr().out
    written = pd.read_csv(out)[["fz_fl", "fz_fr", "fz_rl", "fz_rr"]].to_numpy()
    np.testing.assert_allclose(written, loads, rtol=1e-9)  # CSV round trip of the loads


def test_unknown_suspension_model_is_refused(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["compare", str(example_log_path()), "--vehicle", VEHICLE, "--suspension", "x"])
    assert stop.value.code == 2
    assert "invalid choice: 'x'" in capsys.readouterr().err
