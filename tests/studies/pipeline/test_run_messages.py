"""What ``-v`` and ``-vv`` tell, through the pipeline's own functions: the channels found
and derived, each check's numbers, the phases' times."""

import logging

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.logs.checks import check_wiring
from wheelload.models import load_vehicle
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.run_messages import (
    log_checks,
    log_signals,
    log_vehicle_ranges,
    phase,
)


@pytest.fixture
def caplog(library_caplog):
    """pytest's caplog on the library's own logger (tests/studies/conftest.py)."""
    return library_caplog


def test_a_log_without_rates_or_az_says_what_was_derived(tmp_path, caplog):
    frame = pd.read_csv(example_log_path(), comment="#")
    dropped = [c for c in frame.columns if c.startswith("v_")] + ["az"]
    frame.drop(columns=dropped).to_csv(tmp_path / "lean.csv", index=False)
    signals = read_log(tmp_path / "lean.csv", wiring_checks=False)
    with caplog.at_level(logging.INFO, logger="wheelload"):
        log_signals(signals)
    text = caplog.text
    assert f"read {tmp_path / 'lean.csv'}: 1353 rows at 100 Hz" in text
    assert "derived: v_* (travel rates) from d_*" in text and "az assumed g" in text
    found = next(r.getMessage() for r in caplog.records if "channels found" in r.getMessage())
    assert "v_*" not in found and " az" not in found and "d_fl" in found


def test_the_full_log_derives_nothing(caplog):
    signals = read_log(example_log_path(), wiring_checks=False)
    with caplog.at_level(logging.INFO, logger="wheelload"):
        log_signals(signals, channels="map.toml")
    assert "derived: nothing" in caplog.text and "channel map: map.toml" in caplog.text
    assert "fz_fl fz_fr fz_rl fz_rr" in caplog.text


def test_each_wiring_check_is_told_with_its_statistic_at_debug(caplog):
    signals = read_log(example_log_path(), wiring_checks=False)
    report = check_wiring(signals.t, signals.vx, signals.acc, signals.d, signals.rates)
    with caplog.at_level(logging.DEBUG, logger="wheelload"):
        log_checks("wiring", report)
    lines = [r.getMessage() for r in caplog.records if r.levelno == logging.DEBUG]
    assert len(lines) == len(report.checks) > 3
    check = next(c for c in report.checks if np.isfinite(c.statistic))
    assert any(f"'{check.name}': statistic {check.statistic:.4g}" in line for line in lines)


def test_range_checks_are_told_only_at_debug(caplog):
    from wheelload.models import example_vehicle_path

    vehicle = load_vehicle(example_vehicle_path())
    with caplog.at_level(logging.INFO, logger="wheelload"):
        log_vehicle_ranges(vehicle)
    assert not caplog.records
    with caplog.at_level(logging.DEBUG, logger="wheelload"):
        log_vehicle_ranges(vehicle)
    total = next(r.getMessage() for r in caplog.records if "'mass.total'" in r.getMessage())
    assert total.startswith(f"range check 'mass.total' = {vehicle.mass.total:.4g} in [200,")


def test_a_phase_is_timed_also_when_it_fails(caplog):
    with caplog.at_level(logging.INFO, logger="wheelload"):
        try:
            with phase("checks"):
                raise ValueError("wired wrong")
        except ValueError:
            pass
    (record,) = caplog.records
    assert record.getMessage().startswith("checks: ") and record.getMessage().endswith(" s")
