"""The spike isolation table and the false-alarm bound of ``wheelload bench faults``."""

import dataclasses
import math

import numpy as np
import pytest

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.experiments.faults import fault_spikes as fs
from wheelload.studies.experiments.faults.fault_injection import alarm_bound, pooled_rmse


def test_spike_table_isolates_the_spiked_channel_or_none(vehicle, plant_log):
    """Standstill plant log, one spike per channel at mid-log: every row names no healthy
    channel, and a spike moves the pooled RMSE by less than 1 kN (a 10 mm travel spike
    is one sample of about 300 N on 500 samples; the body rates feed the inertia term)."""
    table = fs.spike_table(TwoStageKF(vehicle), plant_log("standstill"), "standstill", pooled_rmse)
    assert list(table["channel"]) == list(fs.SPIKE_CHANNELS)
    assert (table["healthy_isolated"] == "-").all()
    for _, row in table.iterrows():
        assert row["isolated"] in ("-", row["channel"])
    assert np.all(np.abs(table["rmse_change"]) < 1000.0)


def test_spiked_changes_one_sample_of_one_channel(plant_log):
    signals = plant_log("iso-dlc")
    spiked = fs.spiked(signals, "d_rl", 100)
    difference = spiked.d - signals.d
    assert difference[100, 2] == pytest.approx(0.010)
    assert np.count_nonzero(difference) == 1
    assert np.array_equal(spiked.acc, signals.acc) and spiked.d is not signals.d


def test_spike_on_an_absent_channel_names_it(plant_log):
    signals = dataclasses.replace(plant_log("iso-dlc"), rates=None)
    with pytest.raises(ValueError, match="spike on wx: the log has no rates channel"):
        fs.spiked(signals, "wx", 10)


def test_alarm_bound_is_the_poisson_bound():
    """Zero alarms: P(0 | rate) = exp(-rate T) = 0.05 gives rate = ln(20) / T, so 3.0 h
    bound the rate below 1 per hour; one alarm: the chi^2 bound solves
    exp(-mu) (1 + mu) = 0.05 (checked here to 1e-9)."""
    assert alarm_bound(0, 3.0) == pytest.approx(math.log(20.0) / 3.0, rel=1e-12)
    assert alarm_bound(0, 3.0) < 1.0 < alarm_bound(0, 2.9)
    mu = alarm_bound(1, 1.0)
    assert math.exp(-mu) * (1.0 + mu) == pytest.approx(0.05, abs=1e-9)


def test_bench_prints_the_spike_table(capsys):
    vehicle = str(example_vehicle_path())
    assert main(["bench", "faults", "--spikes", "--model", "paper", "--vehicle", vehicle]) == 0
    out = capsys.readouterr().out
    assert "spikes that isolated a healthy channel: 0 of 30" in out
