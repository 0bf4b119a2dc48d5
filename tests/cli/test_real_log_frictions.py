"""Real logs as users bring them: a missing travel, a missing az, a logger's names.

Each test writes a real log (the bundled lane change with channels removed) and runs the
library's own reader, writer, summary or command on it.
"""

import pandas as pd
import pytest

from wheelload.estimators import read_log, write_log
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import SensorFault
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.cli import main
from wheelload.studies.pipeline.estimate_digest import EstimateDigest
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.summary import LogHeader, summary_text


@pytest.fixture(scope="module")
def plant():
    return pd.read_csv(example_log_path(), comment="#")


def test_identify_without_travel_names_the_missing_channels(plant, tmp_path, capsys):
    """A research car with wheel-force transducers and no travel: the error says so."""
    log = tmp_path / "no_travel.csv"
    plant.drop(columns=[c for c in plant.columns if c[:2] in ("d_", "v_")]).to_csv(log)
    out = tmp_path / "identified.toml"
    args = ["identify", "--vehicle", str(example_vehicle_path()), "--out", str(out)]
    assert main([*args, "--drive", str(log)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith(
        "no suspension travel (d_fl, d_fr, d_rl, d_rr): the maps are fitted to the travels "
        "against the reference loads; log the travel sensors (or map them with --channels)"
    )
    assert len(err.splitlines()) == 1 and not out.exists()


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_an_assumed_az_stays_assumed_through_write_log(plant, tmp_path, suffix):
    log = tmp_path / "no_az.csv"
    plant.drop(columns=["az"]).to_csv(log, index=False)
    signals = read_log(log)
    assert signals.az_assumed
    again = tmp_path / f"again{suffix}"
    write_log(signals, again)
    read_again = read_log(again)
    assert read_again.az_assumed
    assert "no az: g assumed" in read_again.mode()
    assert (read_again.acc == signals.acc).all()


def test_a_fault_on_the_assumed_az_is_not_called_a_sensor_fault(plant, tmp_path):
    log = tmp_path / "no_az.csv"
    plant.drop(columns=["az"]).to_csv(log, index=False)
    signals = read_log(log)
    estimate = TwoStageKF(load_vehicle(example_vehicle_path())).run(signals)
    digest = EstimateDigest(samples=len(estimate), reference_wheels=None)
    digest.add(estimate.loads, estimate.std, estimate.flags)
    header = LogHeader.of(signals, has_reference=False)
    assert header.assumed == ("az",)
    faults = (*estimate.sensor_faults, SensorFault(channel="az", start=5.0, end=6.0, statistic=9.0))
    text = summary_text(header, digest, faults, "sports_car")
    assert "sensor fault: az" not in text
    assert "the assumed az (not in the log) does not hold from 5.00 s to 6.00 s" in text


def test_a_partial_rate_set_is_read_and_its_terms_flagged(plant, tmp_path, capsys):
    """Roll and yaw rate without a pitch rate: the log is read (the two rates kept, the
    pitch rate missing), the terms that need all three are dropped and flagged, and the
    loads stay within 1 N of the full log's pooled RMSE (27.8 N on the bundled log)."""
    log = tmp_path / "no_pitch_rate.csv"
    plant.drop(columns=["wy"]).to_csv(log, index=False)
    signals = read_log(log)
    assert signals.rates.shape[1] == 3
    assert pd.isna(signals.rates[:, 1]).all()
    assert (signals.rates[:, [0, 2]] == plant[["wx", "wz"]].to_numpy()).all()
    vehicle = str(example_vehicle_path())
    assert main(["estimate", str(log), "--vehicle", vehicle]) == 0
    partial = capsys.readouterr().out
    assert main(["estimate", str(example_log_path()), "--vehicle", vehicle]) == 0
    full = capsys.readouterr().out

    def pooled(text: str) -> float:
        return float(next(line for line in text.splitlines() if "POOLED" in line).split()[1])

    assert "samples with a model term dropped (body inertia dropped)" in partial
    assert "wiring checks: 7 passed" in partial  # the rates present are still checked
    assert abs(pooled(partial) - pooled(full)) < 1.0


def test_sensor_sets_on_front_only_references_scores_what_it_can(plant, tmp_path, capsys):
    """Front wheel-force transducers only: the table and the sweep's front column, the
    rear and the log's own split said to be unavailable, exit 0."""
    log = tmp_path / "front_reference.csv"
    plant.drop(columns=["fz_rl", "fz_rr"]).to_csv(log, index=False)
    assert main(["sensor-sets", str(log), "--vehicle", str(example_vehicle_path())]) == 0
    out = capsys.readouterr().out
    assert "the log's own n/a (needs reference loads on all four wheels; no fz_rl, fz_rr)" in out
    sweep = out[out.index("roll_split_front") :].splitlines()[1:]
    assert sweep and all(line.split()[2] == "n/a" for line in sweep)
    assert all(float(line.split()[1]) >= 0 for line in sweep)  # the front error is scored


def test_tune_on_an_imu_only_log_says_which_rows_never_ran(plant, tmp_path, capfd):
    """No travel sensors: the suspension rows never run; tune says so, with no NaN and no
    NumPy warning (capfd: what the process writes, Python warnings included)."""
    log = tmp_path / "imu_only.csv"
    plant.drop(columns=[c for c in plant.columns if c[:2] in ("d_", "v_")]).to_csv(log)
    args = ["tune", str(log), "--vehicle", str(example_vehicle_path()), "--iterations", "5"]
    assert main([*args, "--out", str(tmp_path / "tuned.toml")]) == 0
    out, err = capfd.readouterr()
    assert out.count("suspension_fl n/a (never ran)") == 2  # input and tuned
    assert "nan" not in out.lower()
    assert "Warning" not in err


def test_corner_weights_without_travel_say_what_they_can_and_cannot_do(plant, tmp_path, capsys):
    """IMU only: the corner weights hardly move the loads (the rows they set never run;
    0.5 mN on the written estimates) and the
    summary says so, with their total."""
    log = tmp_path / "imu_only.csv"
    plant.drop(columns=[c for c in plant.columns if c[:2] in ("d_", "v_")]).to_csv(log)
    vehicle = str(example_vehicle_path())
    outputs = []
    for extra in ([], ["--corner-weights", "440,440,366,366"]):
        out = tmp_path / f"loads{len(extra)}.csv"
        assert main(["estimate", str(log), "--vehicle", vehicle, "--out", str(out), *extra]) == 0
        outputs.append(pd.read_csv(out))
    text = capsys.readouterr().out
    assert "corner weights 1612.0 kg in all against the file's 1613.2 kg" in text
    assert "which this log without travel sensors never runs" in text
    loads = [f"fz_{w}" for w in ("fl", "fr", "rl", "rr")]
    assert (outputs[0][loads] - outputs[1][loads]).abs().max().max() < 0.01  # N


def test_many_logs_keep_each_logs_messages(plant, tmp_path, capsys):
    """A folder of logs: each log's wiring-check line printed under its name and kept in
    summary.csv's messages column."""
    folder = tmp_path / "logs"
    folder.mkdir()
    plant.to_csv(folder / "full.csv", index=False)
    plant.drop(columns=["wy"]).to_csv(folder / "no_pitch_rate.csv", index=False)
    out = tmp_path / "out"
    args = ["estimate", str(folder), "--vehicle", str(example_vehicle_path()), "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    summary = pd.read_csv(out / "summary.csv")
    for name in ("full.csv", "no_pitch_rate.csv"):
        assert f"{folder / name}: wiring checks: 7 passed" in printed
        row = summary[summary["log"].str.endswith(name)].iloc[0]
        assert "wiring checks: 7 passed" in row["messages"]
