"""The lean path reads a log once (studies/pipeline/lean_estimate.py): the filter starts
on the log's first chunks and goes on as the rest is read. Its output equals
``TwoStageKF.run`` on the whole log, to the bit (tolerance none: the same compiled
arithmetic), whether the first chunks tell the whole log's channels (one read) or not
(a reference channel first seen later: estimated again from a second read), and
whether the log's first seconds of motion fit in the chunks held or not."""

import logging

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.result import read_estimates
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.pipeline import lean_estimate
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.log_settings import EstimateSettings

AGAIN = "estimated again"


@pytest.fixture
def caplog(library_caplog):
    """pytest's caplog on the library's own logger (tests/studies/conftest.py)."""
    return library_caplog


@pytest.fixture(scope="module")
def long_log() -> pd.DataFrame:
    """The example log repeated to 81 180 rows (more than one chunk), time increasing."""
    example = pd.read_csv(example_log_path())
    frame = pd.concat([example] * 60, ignore_index=True)
    frame["t"] = np.arange(len(frame)) / 100.0
    return frame


def _estimate(frame: pd.DataFrame, folder, caplog) -> tuple[pd.DataFrame, pd.DataFrame, str]:
    path, out = folder / "log.parquet", folder / "loads.csv"
    frame.to_parquet(path, index=False)
    settings = EstimateSettings(vehicle=example_vehicle_path())
    with caplog.at_level(logging.INFO, logger="wheelload"):
        result = lean_estimate.estimate_lean(path, settings, out)
    assert result is not None
    expected = TwoStageKF(load_vehicle(example_vehicle_path())).run(read_log(path)).to_pandas()
    return read_estimates(out), expected, caplog.text


def _assert_equal(written: pd.DataFrame, expected: pd.DataFrame) -> None:
    assert list(written.columns) == list(expected.columns)
    for column in expected.columns:
        assert np.array_equal(written[column].to_numpy(), expected[column].to_numpy()), column


def test_a_log_read_once_equals_run(long_log, tmp_path, caplog):
    written, expected, told = _estimate(long_log, tmp_path, caplog)
    _assert_equal(written, expected)
    assert "chunks read, scanned" in told and AGAIN not in told


def test_a_channel_that_appears_late_is_estimated_again(long_log, tmp_path, caplog):
    frame = long_log.copy()
    frame.loc[:70_000, "fz_fl"] = np.nan  # no reference for FL in the first chunk
    written, expected, told = _estimate(frame, tmp_path, caplog)
    _assert_equal(written, expected)
    assert AGAIN in told


def test_a_log_standing_beyond_the_chunks_held_is_scanned_first(
    long_log, tmp_path, caplog, monkeypatch
):
    monkeypatch.setattr(lean_estimate, "HELD_BYTES", 0)  # the first chunk only
    frame = long_log.copy()
    frame.loc[:70_000, ["vx", "ax", "ay"]] = 0.0  # standing: no wiring window in it
    written, expected, told = _estimate(frame, tmp_path, caplog)
    _assert_equal(written, expected)
    assert "read (scan)" in told and "chunks read, scanned" not in told
