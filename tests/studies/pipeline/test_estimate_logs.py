"""``wheelload estimate`` on real files: reference subsets, warnings, many logs, Dask."""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import Estimate, signals_from_frame
from wheelload.estimators.result import read_estimates
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.pipeline.batch import EstimateSettings, expand_logs, run_logs
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.log_warnings import load_warnings, signal_warnings

VEHICLE = str(example_vehicle_path())


@pytest.fixture(scope="module")
def example():
    return pd.read_csv(example_log_path())


def _metric_rows(text):
    table = text.split("error against")[1].splitlines()[2:]
    return [line.split()[0] for line in table if line.startswith("  ")]


def test_front_only_references_score_the_front_wheels(tmp_path, capsys, example):
    log = tmp_path / "front.csv"
    example.drop(columns=["fz_rl", "fz_rr"]).to_csv(log, index=False)
    out, plot = tmp_path / "est.csv", tmp_path / "est.png"
    assert main(["estimate", str(log), "--vehicle", VEHICLE, "--out", str(out),
                 "--plot", str(plot)]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert _metric_rows(text) == ["FL", "FR", "POOLED"]
    assert out.exists() and plot.stat().st_size > 20_000


def test_a_scoring_error_keeps_the_estimates_and_the_plot(tmp_path, capsys, example):
    log = tmp_path / "empty_reference.csv"
    frame = example.copy()
    frame[["fz_fl", "fz_fr", "fz_rl", "fz_rr"]] = np.nan
    frame.to_csv(log, index=False)
    out, plot = tmp_path / "est.csv", tmp_path / "est.png"
    assert main(["estimate", str(log), "--vehicle", VEHICLE, "--out", str(out),
                 "--plot", str(plot)]) == 0  # fmt: skip
    text = capsys.readouterr().out
    assert "no error metrics: " in text and "empty_reference.csv: no wheel has a finite" in text
    estimates = read_estimates(out)
    assert len(estimates) == len(example) and np.isfinite(estimates["fz_fl"]).all()
    assert plot.stat().st_size > 20_000


def test_old_output_files_with_flags_still_read(tmp_path):
    old = tmp_path / "old.csv"
    pd.DataFrame({"t": [0.0, 0.01], "fz_fl": [4000.0, 4001.0], "flags": [0, 16]}).to_csv(
        old, index=False
    )
    assert list(read_estimates(old)["status"]) == [0, 16]


def test_warnings_a_user_acts_on(example):
    frame = example.copy()
    frame["t"] = frame["t"] * 100.0 / 77.0  # a 77 Hz log
    frame["d_rr"] = 0.0  # a dead sensor logged as zero
    # A speed magnitude. v_fr: on the example log (plant with link loads, which
    # take part of the load transfer past the springs) |v_fl| peaks at 0.048 m/s,
    # below the 0.05 m/s a channel must reach to be judged; |v_fr| reaches 0.052.
    frame["v_fr"] = frame["v_fr"].abs()
    found = signal_warnings(signals_from_frame(frame, source="fs.csv"))
    assert len(found) == 3
    assert "sample rate 77 Hz is below 100 Hz" in found[0]
    assert any("'d_rr' is flat at zero" in warning for warning in found)
    assert any("'v_fr' is never negative" in warning for warning in found)
    assert signal_warnings(signals_from_frame(example, source="ok.csv")) == []


def test_negative_loads_are_counted_with_their_depth():
    loads = np.full((10, 4), 3000.0)
    loads[2:5, 2] = [-100.0, -239.0, -20.0]
    loads[4, 3] = -5.0
    estimate = Estimate(t=np.arange(10.0), loads=loads, std=np.ones((10, 4)),
                        residual=np.zeros((10, 3)), flags=np.zeros(10, dtype=np.int64))  # fmt: skip
    (warning,) = load_warnings(estimate, "fs.csv")
    assert "3 samples with a negative estimated load (down to -239 N on RL)" in warning
    assert "bounded MHE" in warning


@pytest.fixture(scope="module")
def fleet(tmp_path_factory, example):
    """Twelve short plant logs: 3 s windows of the bundled plant log."""
    folder = tmp_path_factory.mktemp("fleet")
    for k in range(12):
        start = 80 * k
        example.iloc[start : start + 300].to_csv(folder / f"log{k:03d}.csv", index=False)
    (folder / "notes.txt").write_text("not a log")
    return folder


def test_many_logs_in_parallel_and_on_dask_equal_the_serial_run(tmp_path, fleet, capsys):
    from distributed import LocalCluster

    paths = expand_logs([str(fleet)])
    assert len(paths) == 12 and expand_logs([str(fleet / "log00*.csv")]) == paths[:10]
    settings = EstimateSettings(vehicle=example_vehicle_path())
    serial = run_logs(paths, settings, None, progress=False)
    assert (serial["error"] == "").all() and (serial["samples"] == 300).all()
    local = run_logs(paths, settings, None, workers=2, progress=False)
    pd.testing.assert_frame_equal(local, serial)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=":0") as cluster:  # fmt: skip
        out = tmp_path / "out"
        assert main(["estimate", str(fleet), "--vehicle", VEHICLE, "--out", str(out),
                     "--dask", cluster.scheduler_address]) == 0  # fmt: skip
    on_dask = pd.read_csv(out / "summary.csv", dtype={"error": "str"})
    on_dask["error"] = on_dask["error"].fillna("")  # CSV writes an empty string as nothing
    pd.testing.assert_frame_equal(on_dask, serial, check_dtype=False, rtol=1e-12)
    assert len(list(out.glob("*.estimates.csv"))) == 12
    assert "12 logs: estimates and summary.csv written" in capsys.readouterr().out


def test_a_bad_log_in_a_fleet_is_a_row_with_its_error(tmp_path, example):
    example.iloc[:200].to_csv(tmp_path / "good.csv", index=False)
    example.iloc[:200].drop(columns=["ax"]).to_csv(tmp_path / "bad.csv", index=False)
    settings = EstimateSettings(vehicle=example_vehicle_path())
    table = run_logs(expand_logs([str(tmp_path)]), settings, None, progress=False)
    assert "bad.csv: missing column 'ax'" in table.loc[0, "error"]
    assert table.loc[1, "error"] == "" and table.loc[1, "samples"] == 200


def test_still_period_reason_and_corner_weights_on_the_command_line(tmp_path, capsys, vehicle):
    from wheelload.studies.drive.synthetic import rest, synthetic_log

    signals = synthetic_log(vehicle, rest(duration=3.0), seed=2)
    frame = signals.to_frame()
    rng = np.random.default_rng(1)
    frame[["ax", "ay"]] += 0.5 * rng.standard_normal((len(frame), 2))  # a noisy IMU at rest
    log = tmp_path / "rest.csv"
    frame.to_csv(log, index=False)
    argv = ["estimate", str(log), "--vehicle", VEHICLE, "--still-period", "1.0"]
    assert main([*argv, "--still-noise", "0"]) == 2
    assert "channel 'ax' varies" in capsys.readouterr().err
    assert main([*argv, "--corner-weights", "430,430,370,370"]) == 0
    text = capsys.readouterr().out
    assert "still period 0-1 s" in text and "from its sample differences" in text
    assert "static loads from corner weights 430,430,370,370 kg" in text
