"""Scenarios end to end: driver inside the cones, log files on disk, the command line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from wheelload.studies.cli import main
from wheelload.studies.drive.scenario_log import LOG_COLUMNS, WHEEL_COLUMNS, metadata_path
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import SCENARIOS, dlc_lanes, scenario_run
from wheelload.studies.drive.simulation import simulate


def test_iso_dlc_stays_inside_the_cones(vehicle):
    frame = simulate(vehicle, scenario_run("iso-dlc", vehicle)).frame
    width = vehicle.plant.body.width
    for start, end, centre, lane in dlc_lanes(vehicle):
        inside = frame[(frame["s"] >= start) & (frame["s"] <= end)]
        # The car's centre may wander (lane - body width) / 2 from the lane centre.
        assert np.abs(inside["n"] - centre).max() < 0.5 * (lane - width)
    assert frame["vx"].iloc[0] == pytest.approx(80 / 3.6, rel=1e-3)
    assert np.abs(frame["ay"]).max() > 5.0  # a real lane change, > 0.5 g


def test_simulate_command_writes_log_metadata_and_plot(tmp_path):
    log = tmp_path / "dlc.csv"
    png = tmp_path / "dlc.png"
    status = main(
        [
            "simulate",
            "iso-dlc",
            "--out",
            str(log),
            "--plot",
            str(png),
            "--seed",
            "4",
            "--noise",
            "0",
        ]
    )
    assert status == 0
    frame = pd.read_csv(log)
    assert tuple(frame.columns) == LOG_COLUMNS + WHEEL_COLUMNS  # the plant logs both
    assert np.isfinite(frame.to_numpy()).all()
    meta = json.loads(metadata_path(log).read_text())
    assert meta["scenario"] == "iso-dlc" and meta["seed"] == 4 and meta["noise_scale"] == 0.0
    assert meta["output_rate_hz"] == 100.0 and meta["internal_rate_hz"] == 1000.0
    assert len(meta["vehicle_sha256"]) == 64
    assert png.stat().st_size > 10_000
    # Noise-free, the log holds the clean truth: az = g before the manoeuvre.
    assert frame["az"].iloc[:300].mean() == pytest.approx(9.80665, abs=1e-3)


def test_parquet_log_and_unknown_suffix(tmp_path):
    log = tmp_path / "slope.parquet"
    assert main(["simulate", "slope-20", "--out", str(log), "--rate", "50"]) == 0
    frame = pd.read_parquet(log)
    assert tuple(frame.columns) == LOG_COLUMNS + WHEEL_COLUMNS  # the plant logs both
    assert np.diff(frame["t"]).mean() == pytest.approx(0.02)
    # On the 20 % grade the measured specific force tilts: ax = g sin(atan 0.2) at steady speed.
    steep = frame[frame["t"] > frame["t"].iloc[-1] - 5.0]
    assert steep["ax"].mean() == pytest.approx(9.80665 * np.sin(np.arctan(0.2)), rel=0.05)
    assert main(["simulate", "slope-20", "--out", str(tmp_path / "x.txt")]) == 2


@pytest.mark.parametrize("name", ["chicane-bank-30", "chicane-incline-20", "accel-in-turn"])
def test_short_scenarios_complete_on_the_road(vehicle, name):
    run = scenario_run(name, vehicle, Options())
    frame = simulate(vehicle, run).frame
    assert frame["s"].iloc[-1] >= run.stop - 1.0
    assert (frame["half_width"] - np.abs(frame["n"])).min() > 0.0
    assert np.abs(frame["n"] - frame["target"]).max() < 1.0


def test_every_scenario_is_registered():
    assert {"iso-dlc", "bounce-sweep", "slope-20", "wheel-lift", "brake-in-turn"} <= set(SCENARIOS)
