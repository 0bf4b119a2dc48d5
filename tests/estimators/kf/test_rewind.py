"""Time-stamped measurements (estimators/kf/rewind.py): rows of absent channels skipped, late
measurements by rewind and replay, the synchronous filter's numbers on a synchronous log.

Tolerances: the timed filter and its independent reference run the same IEEE operations in
the same order (the compiled step is bit-identical to CasADi's virtual machine,
tests/estimators/loops/test_fast_step.py), so the comparisons ask for 1e-9 N where the brief
allows it and get 0.
"""

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from wheelload.estimators.kf.rewind import RewindSettings, measurements
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS

sys.path.insert(0, str(Path(__file__).parents[2]))
from timed_logs import (  # noqa: E402
    can_car_log,
    latencies,
    time_ordered_reference,
    union_frame,
)

TOO_OLD = int(StepFlag.MEASUREMENT_TOO_OLD)
SUSPENSION = int(sum(tuple(StepFlag)[:4]))
EQUILIBRIUM = int(StepFlag.VERTICAL_SKIPPED | StepFlag.PITCH_SKIPPED | StepFlag.ROLL_SKIPPED)


@pytest.fixture(scope="module")
def dlc(plant_log):
    return plant_log("iso-dlc")


@pytest.fixture(scope="module")
def kf(vehicle):
    return TwoStageKF(vehicle, sample_interval=0.005, check_file=False)


@pytest.fixture(scope="module")
def can_run(kf, dlc):
    t, inputs = can_car_log(dlc, 5.0)
    run = kf.run_timed(t, inputs, latencies())
    return t, inputs, run


def test_synchronous_in_order_log_gives_the_synchronous_filter_bit_for_bit(vehicle, dlc):
    kf = TwoStageKF(vehicle, sample_interval=0.01, check_file=False)
    timed = kf.run_timed(dlc.t, input_matrix(dlc).T, first_interval=dlc.t[1] - dlc.t[0])
    synchronous = kf.run(dlc)
    assert timed.rewinds == 0 and timed.dropped == 0
    np.testing.assert_array_equal(timed.arrival_loads, synchronous.loads)
    np.testing.assert_array_equal(timed.loads, synchronous.loads)
    np.testing.assert_array_equal(timed.std, synchronous.std)
    np.testing.assert_array_equal(timed.arrival_flags, synchronous.flags)


def test_the_input_flags_are_ored_in_as_run_does(vehicle, dlc):
    """A log without az (g assumed, flagged on every row by ``run``): the timed filter's
    flags carry the bit too, and equal ``run``'s bit for bit."""
    no_az = dataclasses.replace(dlc, acc=np.column_stack([dlc.acc[:, :2], np.full(len(dlc), 9.81)]),
                                az_assumed=True)  # fmt: skip
    kf = TwoStageKF(vehicle, sample_interval=0.01, check_file=False)
    timed = kf.run_timed(no_az.t, input_matrix(no_az).T, first_interval=dlc.t[1] - dlc.t[0],
                         input_flags=no_az.input_flags())  # fmt: skip
    synchronous = kf.run(no_az)
    assert np.all(timed.flags & int(StepFlag.AZ_ASSUMED_G))
    np.testing.assert_array_equal(timed.flags, synchronous.flags)
    np.testing.assert_array_equal(timed.arrival_flags, synchronous.flags)


def test_only_the_rows_of_absent_channels_are_skipped(kf, can_run):
    """A travel frame updates the four suspension rows and no equilibrium row, an IMU frame
    the three equilibrium rows (the speed held from its own frame) and no suspension row."""
    t, inputs, run = can_run
    stamps, channels = measurements(t, inputs, latencies())
    kept = run.flags != TOO_OLD
    travel = kept & np.isfinite(channels[:, INPUTS.index("d_fl")])
    imu = kept & np.isfinite(channels[:, INPUTS.index("ax")])
    speed = kept & ~travel & ~imu
    assert travel.sum() > 400 and imu.sum() > 900 and speed.sum() > 200
    assert np.all(run.flags[travel] & SUSPENSION == 0)
    assert np.all(run.flags[travel] & EQUILIBRIUM == EQUILIBRIUM)
    assert np.all(run.flags[imu] & SUSPENSION == SUSPENSION)
    assert np.all(run.flags[imu] & EQUILIBRIUM == 0)
    assert np.all(run.flags[speed] & (SUSPENSION | EQUILIBRIUM) == SUSPENSION | EQUILIBRIUM)
    # No travel frame is taken for a jump: between two of them IMU frames come 1 ms apart.
    assert not np.any(run.flags[kept] & int(StepFlag.TRAVEL_JUMP | StepFlag.INTERVAL_SHORT))


def test_rewinds_give_the_measurements_fed_in_time_order(kf, can_run):
    t, inputs, run = can_run
    stamps, channels = measurements(t, inputs, latencies())
    assert run.rewinds > 300, "late (latency) and out-of-order frames rewound"
    assert run.dropped == 3 and np.sum(run.flags == TOO_OLD) == 3, "the three far too late"
    kept = run.flags != TOO_OLD
    loads, unique = time_ordered_reference(
        kf, stamps, channels, kept, speed_hold=RewindSettings().speed_hold,
        first_interval=0.005,
    )  # fmt: skip
    # The timed filter's final estimate at each time stamp (the last of merged ones).
    order = np.argsort(stamps[kept], kind="stable")
    sorted_stamps, sorted_loads = stamps[kept][order], run.loads[kept][order]
    last = np.r_[sorted_stamps[1:] != sorted_stamps[:-1], True]
    np.testing.assert_array_equal(sorted_stamps[last], unique)
    np.testing.assert_allclose(sorted_loads[last], loads, rtol=0, atol=1e-9)
    # What a running filter showed: the time-ordered estimate at its newest stamp, where no
    # measurement of an older stamp was still to come.
    assert np.all(np.isfinite(run.arrival_loads))


def test_a_log_on_its_own_clocks_runs_as_the_timed_filter_runs_its_rows(kf, dlc):
    """``run`` on channels on their own clocks (``[clock] union``; travel rates and body-rate
    derivatives derived on each channel's own stamps) is the timed filter fed the rows in
    time order, each at its own stamp: 1e-9 N (0 measured), the flags equal. (Up to the
    last speed sample: beyond it the log has no speed, the timed filter holds the last.)"""
    signals = signals_from_frame(union_frame(dlc, 5.0), wiring_checks=False, own_clocks=True)
    signals = signals.slice(0, int(np.flatnonzero(np.isfinite(signals.vx))[-1]) + 1)
    run = kf.run(signals)
    timed = kf.run_timed(
        signals.t,
        input_matrix(signals, kf.rate_filter).T,
        first_interval=signals.t[1] - signals.t[0],
    )
    assert timed.loads.shape == run.loads.shape and timed.rewinds == 0
    np.testing.assert_allclose(timed.loads, run.loads, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(timed.flags, run.flags)
    travel = np.isfinite(signals.d[:, 0])
    assert np.all(np.isfinite(signals.v[travel])) and np.all(run.flags[travel] & SUSPENSION == 0)
    assert not np.any(run.flags & int(StepFlag.INTERVAL_SHORT | StepFlag.INTERVAL_LONG))


def test_a_stuck_travel_on_a_timed_log_is_isolated_on_time(kf, dlc):
    """The stuck test counts the seconds a travel has not changed, not the rows: on a log
    whose rows come about 3.5 times as often as the travel frames, d_fl frozen at 6 s in
    the lane change is isolated once it has been still for ``stuck_time`` (to within one
    10 ms travel frame and its 0.6 ms of jitter); counting rows it took 1.10 s."""
    t, inputs = can_car_log(dlc, 9.0, far_late=0)
    stamps, channels = measurements(t, inputs, latencies())
    frozen_at, d_fl, v_fl = 6.0, INPUTS.index("d_fl"), INPUTS.index("v_fl")
    stuck = (stamps >= frozen_at) & np.isfinite(channels[:, d_fl])
    first = np.flatnonzero(stuck)[np.argmin(stamps[stuck])]
    inputs = inputs.copy()
    rows = np.isfinite(inputs[:, d_fl]) & (t - latencies()["d_fl"] >= stamps[first])
    inputs[rows, d_fl], inputs[rows, v_fl] = channels[first, d_fl], 0.0
    run = kf.run_timed(t, inputs, latencies())
    faulty = (run.flags != TOO_OLD) & (run.flags & int(StepFlag.TRAVEL_FAULT) != 0)
    assert faulty.any(), "the stuck d_fl is isolated"
    delay = np.min(run.stamps[faulty]) - stamps[first]
    stuck_time = kf.guard_settings.stuck_time
    assert stuck_time <= delay <= stuck_time + 0.0106


def test_a_small_ring_drops_what_is_older_than_its_oldest_checkpoint(kf):
    u = np.full(len(INPUTS), np.nan)
    u[INPUTS.index("ax") : INPUTS.index("vx") + 1] = (0.0, 0.0, 9.81, 20.0)
    timed = kf.timed(RewindSettings(checkpoints=3, max_rewind_age=1.0))
    for t in (0.01, 0.02, 0.03, 0.04):
        assert timed.update_at(t, u) & TOO_OLD == 0
    assert timed.update_at(0.025, u) & TOO_OLD == 0  # between checkpoints: replayed
    assert timed.rewinds == 1 and timed.replayed == 2
    assert timed.update_at(0.021, u) == TOO_OLD  # before the oldest of a full ring
    assert timed.update_at(np.nan, u) == TOO_OLD
    assert timed.dropped == 2 and timed.time == 0.04
    loose = kf.timed(RewindSettings(checkpoints=8, max_rewind_age=0.005))
    for t in (0.01, 0.02, 0.03):
        loose.update_at(t, u)
    assert loose.update_at(0.024, u) == TOO_OLD  # beyond max_rewind_age
    assert loose.update_at(0.026, u) & TOO_OLD == 0


def test_a_late_channel_merges_into_its_time_stamp(kf, dlc):
    """Travel and IMU of one instant sent in two frames, the travel late, equal the two in
    one row."""
    whole = input_matrix(dlc).T[:60]
    together = kf.timed(first_interval=0.01)
    apart = kf.timed(first_interval=0.01)
    travel = np.zeros(len(INPUTS), bool)
    travel[: INPUTS.index("ax")] = True
    for k, u in enumerate(whole):
        together.update_at(dlc.t[k], u)
        rest = np.where(travel, np.nan, u)
        apart.update_at(dlc.t[k], rest)
        if k >= 2:
            apart.update_at(dlc.t[k - 2], np.where(travel, whole[k - 2], np.nan))
    apart.update_at(dlc.t[58], np.where(travel, whole[58], np.nan))
    apart.update_at(dlc.t[59], np.where(travel, whole[59], np.nan))
    np.testing.assert_allclose(apart.loads, together.loads, rtol=0, atol=1e-9)
    assert apart.rewinds == 60


def test_settings_refuse_what_cannot_work():
    with pytest.raises(ValueError, match="checkpoints must be 1 to 65536, got 0"):
        RewindSettings(checkpoints=0)
    with pytest.raises(ValueError, match="max_rewind_age must be >= 0 s and finite"):
        RewindSettings(max_rewind_age=-1.0)
    with pytest.raises(ValueError, match="latency: one value >= 0 s per channel"):
        measurements(np.zeros(1), np.zeros((1, len(INPUTS))), np.full(3, 0.01))
    with pytest.raises(ValueError, match="latency: no input channel a_y; the channels are"):
        measurements(np.zeros(1), np.zeros((1, len(INPUTS))), {"a_y": 0.3})
