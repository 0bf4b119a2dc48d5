"""Input plausibility on a plant log: an implausible sample is treated exactly as a missing one.

The log is the ISO lane change simulated by the full-vehicle plant with the
standard sensor models (``run_scenario``, fixture ``dlc``); the reference loads are the
plant's. The outlier's estimate equals, bitwise, the estimate of the same log with the
outlier replaced by a missing value; the carried state stays finite whatever the input.
"""

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators import Sample, StepFlag
from wheelload.estimators.guards.monitor_state import CREDIT, HELD, MONITOR_SIZE
from wheelload.estimators.guards.plausibility import rate_consistency
from wheelload.estimators.guards.settings import GUARDS_OFF, GuardSettings
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models.inputs import BODY_RATES, INPUTS

ROWS_SKIPPED = sum(StepFlag.update_flags())


ISSUE_OUTLIERS = [
    ({"ax": 50.0}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"ay": 100.0}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"d_fl": 0.29}, StepFlag.TRAVEL_IMPLAUSIBLE),
    ({"ax": 1e30}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"vx": 500.0}, StepFlag.SPEED_IMPLAUSIBLE),  # aero terms only: a small effect unguarded
]


@pytest.mark.parametrize(("values", "flag"), ISSUE_OUTLIERS)
def test_implausible_sample_is_skipped_exactly_and_flagged(vehicle, dlc, values, flag, with_values):
    kf = TwoStageKF(vehicle)
    row = 600
    outlier = kf.run(with_values(dlc, row, **values))
    missing = kf.run(with_values(dlc, row, **{name: np.nan for name in values}))
    np.testing.assert_array_equal(outlier.loads, missing.loads)  # skipped like a missing input
    assert outlier.flags[row] & flag
    assert outlier.flags[row] & ROWS_SKIPPED == missing.flags[row] & ROWS_SKIPPED != 0
    assert np.count_nonzero(outlier.flags & flag) == 1
    assert np.max(np.abs(outlier.loads[row] - dlc.reference[row])) < 150.0
    if flag is not StepFlag.SPEED_IMPLAUSIBLE:
        # Without the guards the same sample moves the loads by hundreds of N or more.
        unguarded = TwoStageKF(vehicle, guard_settings=GUARDS_OFF)
        moved = unguarded.run(with_values(dlc, row, **values)).loads[row]
        assert np.max(np.abs(moved - dlc.reference[row])) > 300.0


def test_monitor_state_stays_finite_with_missing_and_implausible_inputs(vehicle, dlc):
    """Every channel missing or absurd in turn: the carried monitor state stays finite."""
    kf = TwoStageKF(vehicle)
    state = kf.initial_state()
    for k, value in enumerate([np.nan, np.inf, 1e30, -1e30, 0.0] * 12):
        u = np.concatenate([dlc.d[k], dlc.v[k], dlc.acc[k], [dlc.vx[k]]])
        u[k % 12] = value
        sample = Sample(d=u[0:4], v=u[4:8], acc=u[8:11], vx=u[11])
        state, estimate = kf.step(state, sample, 0.01)
        assert np.isfinite(state.m).all() and np.isfinite(state.x).all()
        assert np.isfinite(state.P).all()


def test_a_body_rate_jump_faster_than_any_body_turns_is_not_taken():
    """rate_consistency on a constructed monitor state: each body rate held at 0.1 rad/s,
    its hold credit 10 ms into the hold time; a new sample that moved by more than
    max_angular_acceleration x 10 ms is not taken (0), one that moved by less is (1), and
    a jump sets the derivative's settling time. Exact."""
    g = GuardSettings()
    elapsed = 0.01
    rates = [INPUTS.index(name) for name in BODY_RATES]
    m = np.zeros(MONITOR_SIZE)
    m[HELD] = 0.1
    m[CREDIT] = g.hold_time - elapsed
    ones = ca.DM.ones(len(INPUTS))
    for step, taken in ((0.5, 1.0), (1.5, 0.0)):
        u = np.zeros(len(INPUTS))
        u[rates] = 0.1 + step * g.max_angular_acceleration * elapsed
        ok, settle = rate_consistency(ca.DM(u), ones, ones, ca.DM(m), 0.0, g)
        np.testing.assert_array_equal(np.asarray(ok).ravel()[rates], taken)
        expected = 0.0 if taken else g.rate_settle_time
        np.testing.assert_array_equal(np.asarray(settle).ravel(), expected)
