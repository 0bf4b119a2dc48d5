"""Logs as real loggers write them, from the plant's ISO lane change written to disk: an IMU
axis at a lower rate or empty, a time gap, a slow speed channel, date-time stamps.

Each variant is scored against the plant's reference loads beside the full-rate log of the
same run (the two-stage KF, fixed mass); the tolerances are stated per test.
"""

import logging

import numpy as np
import pandas as pd
import pytest
from asammdf import MDF, Signal

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.signals import derive_velocities, read_log
from wheelload.estimators.result import StepFlag
from wheelload.estimators.types import LogError
from wheelload.models.conventions import WHEELS

TRAVEL_RATE = [f"v_{w}" for w in WHEELS]


@pytest.fixture(scope="module")
def plant_frame(plant_log):
    """The lane change's log as written by ``wheelload simulate`` (reference loads, no v_*:
    the velocities are derived, as from a logger)."""
    return plant_log("iso-dlc").to_frame().drop(columns=TRAVEL_RATE)


@pytest.fixture(scope="module")
def kf(fixed_vehicle):
    return TwoStageKF(fixed_vehicle)


def rmse(estimate, reference, rows=slice(None)):
    error = estimate.loads[rows] - reference[rows]
    return float(np.sqrt(np.mean(error[np.isfinite(error)] ** 2)))


@pytest.fixture(scope="module")
def full_rmse(plant_frame, kf, tmp_path_factory):
    path = tmp_path_factory.mktemp("full") / "full.csv"
    plant_frame.to_csv(path, index=False)
    signals = read_log(path)
    return rmse(kf.run(signals), signals.reference)


@pytest.mark.parametrize("axis", ["ax", "ay"])
@pytest.mark.parametrize("every", [2, 3])
def test_an_imu_axis_at_a_lower_rate_runs_and_skips_its_missing_rows(
    plant_frame, kf, full_rmse, tmp_path, axis, every
):
    """ax or ay logged at a half or a third of the rate (NaN where it has no new value): the
    wiring checks use the rows where it exists (a third stopped them with KeyError before),
    every row without it has an update skipped (flagged), no estimate is NaN, and the RMSE
    stays within 10 % of the full-rate log's (measured: within 1 %)."""
    frame = plant_frame.copy()
    missing = np.arange(len(frame)) % every != 0
    frame.loc[missing, axis] = np.nan
    path = tmp_path / "slow_axis.csv"
    frame.to_csv(path, index=False)
    signals = read_log(path)
    estimate = kf.run(signals)
    assert np.isfinite(estimate.loads).all()
    skipped = (estimate.flags & StepFlag.skipped_mask()) != 0
    assert skipped[missing].all()
    assert rmse(estimate, signals.reference) < 1.1 * full_rmse


@pytest.mark.parametrize("axis", ["ax", "ay"])
def test_an_empty_imu_axis_is_one_line_naming_it(plant_frame, tmp_path, axis):
    path = tmp_path / "empty.csv"
    plant_frame.assign(**{axis: np.nan}).to_csv(path, index=False)
    with pytest.raises(LogError, match=f"column '{axis}' has no values") as error:
        read_log(path)
    assert "\n" not in str(error.value)


def test_an_empty_az_is_assumed_g_and_flagged(plant_frame, kf, tmp_path):
    path = tmp_path / "empty_az.csv"
    plant_frame.assign(az=np.nan).to_csv(path, index=False)
    signals = read_log(path)
    assert signals.az_assumed
    estimate = kf.run(signals)
    assert np.all(estimate.flags & StepFlag.AZ_ASSUMED_G)


def test_a_gap_in_a_csv_splits_the_log_into_segments(
    plant_frame, kf, full_rmse, tmp_path, caplog, monkeypatch
):
    """5 s missing from a CSV without v_* (refused before: "not uniform enough"): each
    segment's velocities are the differentiator run on that segment alone (to 1e-12 m/s), the
    first step after the gap is flagged INTERVAL_LONG (and said in a note), and the RMSE over
    the kept rows is within 10 % of the full-rate log's (the filter holds its state over the
    gap)."""
    t = plant_frame["t"].to_numpy()
    keep = (t < 4.0) | (t >= 9.0)
    path = tmp_path / "gap.csv"
    plant_frame[keep].to_csv(path, index=False)
    monkeypatch.setattr(logging.getLogger("wheelload"), "handlers", [caplog.handler])
    monkeypatch.setattr(logging.getLogger("wheelload"), "propagate", False)
    with caplog.at_level(logging.WARNING, logger="wheelload"):
        signals = read_log(path)
    assert "1 gap(s) in the time stamps (longest 5.01 s" in caplog.text
    first = np.flatnonzero(signals.t >= 9.0)[0]
    d = signals.d
    separate = np.vstack(
        [
            derive_velocities(signals.t[:first], d[:first]),
            derive_velocities(signals.t[first:], d[first:]),
        ]
    )
    # the segments' median intervals differ from the whole log's in the last bits
    np.testing.assert_allclose(signals.v, separate, rtol=0, atol=1e-12)
    estimate = kf.run(signals)
    assert estimate.flags[first] & StepFlag.INTERVAL_LONG
    assert np.isfinite(estimate.loads).all()
    assert rmse(estimate, signals.reference) < 1.1 * full_rmse


def _write_mdf(path, groups):
    """An MF4 with one channel group per ``(t, {name: values})``."""
    mdf = MDF(version="4.10")
    for t, channels in groups:
        mdf.append([Signal(samples=np.asarray(v, float), timestamps=t, name=n, unit="")
                    for n, v in channels.items()])  # fmt: skip
    mdf.save(path, overwrite=True)
    mdf.close()


def test_a_gap_in_an_mf4_clock_group_is_not_refused(plant_frame, kf, full_rmse, tmp_path):
    """0.5 s missing from the MF4 clock group (refused before): the log runs, within 10 % of
    the full-rate RMSE over its rows."""
    t = plant_frame["t"].to_numpy()
    keep = (t < 6.0) | (t >= 6.5)
    columns = {c: plant_frame[c].to_numpy()[keep] for c in plant_frame.columns if c != "t"}
    path = tmp_path / "gap.mf4"
    _write_mdf(path, [(t[keep], columns)])
    signals = read_log(path)
    assert len(signals) == keep.sum()
    estimate = kf.run(signals)
    assert np.isfinite(estimate.loads).all()
    assert rmse(estimate, signals.reference) < 1.1 * full_rmse


@pytest.mark.parametrize("suffix", [".csv", ".mf4"])
def test_a_1_hz_speed_is_interpolated_onto_the_log_clock(
    plant_frame, kf, full_rmse, tmp_path, suffix, caplog, monkeypatch
):
    """vx at 1 Hz (a CAN speed): interpolated linearly between its samples onto the 100 Hz
    clock (said on the wheelload logger), not dropped on 99 % of the rows; vx equals
    ``np.interp`` of its samples, and the RMSE is within 10 % of the full-rate log's (it was
    2.9x with the speed missing between samples)."""
    t = plant_frame["t"].to_numpy()
    slow = np.isclose(np.mod(t + 1e-9, 1.0), 0.0, atol=1e-6)
    path = tmp_path / f"slow_speed{suffix}"
    if suffix == ".csv":
        plant_frame.assign(vx=np.where(slow, plant_frame["vx"], np.nan)).to_csv(path, index=False)
    else:
        fast = {c: plant_frame[c].to_numpy() for c in plant_frame.columns if c not in ("t", "vx")}
        _write_mdf(path, [(t, fast), (t[slow], {"vx": plant_frame["vx"].to_numpy()[slow]})])
    # the command line's logging setup (an earlier test in this process) may stop the
    # "wheelload" logger propagating to the root, where caplog listens: listen on it
    monkeypatch.setattr(logging.getLogger("wheelload"), "handlers", [caplog.handler])
    monkeypatch.setattr(logging.getLogger("wheelload"), "propagate", False)
    with caplog.at_level(logging.WARNING, logger="wheelload"):
        signals = read_log(path)
    assert "interpolated linearly" in caplog.text
    inside = (t >= t[slow][0]) & (t <= t[slow][-1])
    expected = np.interp(t[inside], t[slow], plant_frame["vx"].to_numpy()[slow])
    np.testing.assert_allclose(signals.vx[inside], expected, rtol=0, atol=1e-9)
    estimate = kf.run(signals)
    assert rmse(estimate, signals.reference) < 1.1 * full_rmse


@pytest.mark.parametrize("unit", ["ns", "us", "ms"])
@pytest.mark.parametrize("zone", [None, "Europe/Berlin"])
def test_a_parquet_timestamp_column_is_read_as_seconds(plant_frame, tmp_path, unit, zone):
    """``timestamp[ns/us/ms]`` with or without a time zone (refused before as a column of the
    wrong type): seconds from the first stamp, to the stamp's resolution."""
    t = plant_frame["t"].to_numpy()
    nanoseconds = 1_700_000_000 * 10**9 + np.round(t * 1e9).astype(np.int64)
    stamps = pd.Series(pd.to_datetime(nanoseconds, unit="ns", utc=zone is not None))
    if zone is not None:
        stamps = stamps.dt.tz_convert(zone)
    stamps = stamps.astype(f"datetime64[{unit}, {zone}]" if zone else f"datetime64[{unit}]")
    path = tmp_path / "stamps.parquet"
    plant_frame.assign(t=stamps.to_numpy() if zone is None else stamps.array).to_parquet(path)
    signals = read_log(path)
    resolution = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3}[unit]
    np.testing.assert_allclose(signals.t, t - t[0], rtol=0, atol=resolution + 1e-7)


def test_a_slow_channel_in_a_map_is_bridged_over_its_own_interval(plant_frame, tmp_path):
    """The channel-map path: a 1 Hz vx under ``clock.max_gap = 0.1`` s is resampled over gaps
    up to 1.5 of its own intervals, so only the rows outside its span are missing."""
    from wheelload.estimators.logs.readers.channel_map import slow_gap

    t = np.arange(0.0, 10.0 + 1e-9, 1.0)
    assert slow_gap(t, 0.1) == pytest.approx(1.5)
    assert slow_gap(np.arange(0.0, 1.0, 0.01), 0.1) == 0.1
