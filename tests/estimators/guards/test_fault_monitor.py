"""Sensor-fault detection and isolation on plant logs (issue 8, item 3).

Faults are injected from 20 % of the ISO lane change and the brake-in-turn
logs of the full-vehicle plant (``studies/experiments/faults/fault_injection.py``); errors are
against the plant's reference loads. Delays are stated against the
monitor's settings: a dead sensor (a jump to its rail, then frozen) within
``stuck_time`` + one sample, a stuck one within ``stuck_time`` once another
corner moves, ``stuck_time_still`` on a still body (goal 0.5 s); a 1 mm/s
drift once the low-passed parity residual exceeds ``travel_fault`` (5 mm),
i.e. within 8 s (goal 2 s, not met: see the closing note).
"""

import numpy as np
import pytest

from wheelload.estimators import StepFlag, write_log
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.experiments.faults import fault_injection as fi


@pytest.fixture(scope="module")
def logs(plant_log):
    return {name: plant_log(name) for name in ("iso-dlc", "brake-in-turn", "wheel-lift")}


def inject(signals, fault):
    k = int(fi.ONSET * len(signals))
    return fault.inject(signals, k, np.random.default_rng(0)), signals.t[k]


FAULTS = {fault.name: fault for fault in fi.FAULTS}


@pytest.mark.parametrize("scenario", ["iso-dlc", "brake-in-turn"])
@pytest.mark.parametrize("name", ["stuck", "dead"])
def test_stuck_or_dead_travel_sensor_isolated_within_half_a_second(vehicle, logs, scenario, name):
    signals, onset = inject(logs[scenario], FAULTS[name])
    guarded = TwoStageKF(vehicle).run(signals)
    unguarded = TwoStageKF(vehicle, guard_settings=fi.GUARDS_OFF).run(signals)
    faults = guarded.faults
    assert list(faults["channel"]) == ["d_fl"]
    delay = fi.detection_delay(faults, "d_fl", onset)
    settings = GuardSettings()
    if name == "dead":  # the jump to the rail is the evidence: stuck_time
        assert delay <= settings.stuck_time + 0.011
    else:  # stuck_time once another corner moves, stuck_time_still on a still body
        assert delay <= settings.stuck_time_still + 0.011 <= 0.52
    assert faults["end"].iloc[0] == pytest.approx(signals.t[-1])
    assert faults["statistic"].iloc[0] >= 1.0
    flagged = guarded.flags & StepFlag.TRAVEL_FAULT != 0
    assert np.array_equal(flagged, (signals.t >= faults["start"].iloc[0]))
    # Dropped from the updates: FL (and FR, coupled through the anti-roll bar) skipped.
    skipped = StepFlag.SUSPENSION_FL_SKIPPED | StepFlag.SUSPENSION_FR_SKIPPED
    assert np.all(guarded.flags[flagged] & skipped == skipped)
    after = fi.pooled_rmse(guarded.loads, signals.reference)
    before = fi.pooled_rmse(unguarded.loads, signals.reference)
    # Plant with link forces: the stuck sensor costs the unguarded filter 132 N on iso-dlc
    # (212-1917 N elsewhere); the guarded one 36-95 N: at least 3 x better everywhere.
    assert after < 100.0 and 3.0 * after < before


def test_drifting_travel_sensor_isolated(vehicle, logs):
    signals, onset = inject(logs["brake-in-turn"], FAULTS["drift"])
    estimate = TwoStageKF(vehicle).run(signals)
    assert set(estimate.faults["channel"]) == {"d_fl"}
    assert fi.detection_delay(estimate.faults, "d_fl", onset) < 8.0
    before = TwoStageKF(vehicle, guard_settings=fi.GUARDS_OFF).run(signals)
    assert fi.pooled_rmse(estimate.loads, signals.reference) < 0.5 * fi.pooled_rmse(
        before.loads, signals.reference
    )


@pytest.mark.parametrize("scenario", ["iso-dlc", "brake-in-turn", "wheel-lift"])
def test_no_false_alarm_on_clean_plant_logs(vehicle, logs, scenario):
    estimate = TwoStageKF(vehicle).run(logs[scenario])
    assert estimate.faults.empty
    assert not np.any(estimate.flags & (StepFlag.TRAVEL_FAULT | StepFlag.IMU_FAULT))


def test_accelerometer_fault_isolated_by_its_axis(vehicle, logs):
    """A 3 m/s^2 ay offset is named as ay (not a travel channel) and the roll row dropped."""
    signals = logs["iso-dlc"]
    k = int(fi.ONSET * len(signals))
    acc = signals.acc.copy()
    acc[k:, 1] += 3.0
    faulty = type(signals)(**{**signals.__dict__, "acc": acc})
    estimate = TwoStageKF(vehicle).run(faulty)
    assert list(estimate.faults["channel"]) == ["ay"]
    flagged = estimate.flags & StepFlag.IMU_FAULT != 0
    assert np.all(estimate.flags[flagged] & StepFlag.ROLL_SKIPPED)
    assert fi.detection_delay(estimate.faults, "ay", signals.t[k]) < 2.0


@pytest.mark.parametrize("axis", [0, 2], ids=["ax", "az"])
def test_a_longitudinal_or_vertical_accelerometer_fault_is_no_travel_fault(vehicle, logs, axis):
    """A 3 m/s^2 offset on ax or az is named as that axis, flagged as an IMU fault from
    its confirmation on, and never as a travel fault."""
    signals = logs["iso-dlc"]
    k = int(fi.ONSET * len(signals))
    acc = signals.acc.copy()
    acc[k:, axis] += 3.0
    estimate = TwoStageKF(vehicle).run(type(signals)(**{**signals.__dict__, "acc": acc}))
    name = ("ax", "ay", "az")[axis]
    assert list(estimate.faults["channel"]) == [name]
    imu = estimate.flags & StepFlag.IMU_FAULT != 0
    np.testing.assert_array_equal(imu, signals.t >= estimate.faults["start"].iloc[0])
    assert not np.any(estimate.flags & StepFlag.TRAVEL_FAULT)


def test_estimate_command_reports_the_fault(logs, tmp_path, capsys):
    signals, onset = inject(logs["iso-dlc"], FAULTS["dead"])
    log = tmp_path / "dead.csv"
    write_log(signals, log)
    assert main(["estimate", str(log), "--vehicle", str(example_vehicle_path())]) == 0
    out = capsys.readouterr().out
    assert f"sensor fault: d_fl from {onset + GuardSettings().stuck_time:.2f}" in out
    assert "travel_fault" in out
