"""Guards of the filter step on a plant log: plausibility, innovation gate, gaps, bad tuning.

The log is the ISO lane change simulated by the full-vehicle plant with the
standard sensor models (``run_scenario``); the reference loads are the
plant's. Exactness checks compare with an independent numpy Kalman filter
(tolerance 1e-9 relative: same arithmetic in another order) or with the same
log where the outlier is replaced by a missing value (bitwise: an
implausible input is treated exactly as a missing one).
"""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators import Sample, StepFlag, TwoStageKF
from wheelload.estimators.kf.guard import GuardSettings
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import sample_intervals
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.models import GRAVITY, equilibrium_function, gates_function, suspension_function
from wheelload.studies.experiments.faults.fault_injection import GUARDS_OFF, pooled_rmse

ROWS_SKIPPED = sum(StepFlag.update_flags())


@pytest.fixture(scope="module")
def dlc(plant_log):
    return plant_log("iso-dlc")


def with_values(signals, row, **values):
    """A copy of ``signals`` with single samples replaced: ``ax=50``, ``d_fl=0.29``, ..."""
    d, v, acc, vx = signals.d.copy(), signals.v.copy(), signals.acc.copy(), signals.vx.copy()
    for name, value in values.items():
        if name in ("ax", "ay", "az"):
            acc[row, "xyz".index(name[1])] = value
        elif name == "vx":
            vx[row] = value
        else:
            target = d if name[0] == "d" else v
            target[row, ("fl", "fr", "rl", "rr").index(name[2:])] = value
    return dataclasses.replace(signals, d=d, v=v, acc=acc, vx=vx)


ISSUE_OUTLIERS = [
    ({"ax": 50.0}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"ay": 100.0}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"d_fl": 0.29}, StepFlag.TRAVEL_IMPLAUSIBLE),
    ({"ax": 1e30}, StepFlag.ACCELERATION_IMPLAUSIBLE),
    ({"vx": 500.0}, StepFlag.SPEED_IMPLAUSIBLE),  # aero terms only: a small effect unguarded
]


@pytest.mark.parametrize(("values", "flag"), ISSUE_OUTLIERS)
def test_implausible_sample_is_skipped_exactly_and_flagged(vehicle, dlc, values, flag):
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


def reference_step(kf, x, P, signals, k, dt, rows):
    """Independent numpy step: predict, then the scalar updates of ``rows`` only (0-6)."""
    u_raw = input_matrix(signals)[:, k]
    u, valid = np.nan_to_num(u_raw), np.isfinite(u_raw).astype(float)
    gates = gates_function()(valid, kf.p)[0]
    z = np.asarray(suspension_function()(u, gates, kf.p)).ravel()
    A, b = (np.asarray(a) for a in equilibrium_function()(u, gates, kf.p))
    nominal = nominal_interval(signals.t)
    q, r_s, r_c = kf.tuning[0], kf.tuning[1], kf.tuning[2:5]
    H = np.vstack([np.eye(4), A])
    y_all = np.concatenate([z, b.ravel()])
    r = np.concatenate([np.full(4, r_s), r_c]) / nominal
    P = P + q * dt * np.eye(4)
    for i in rows:
        h = H[i]
        S = h @ P @ h + r[i]
        K = P @ h / S
        x = x + K * (y_all[i] - h @ x)
        I_KH = np.eye(4) - np.outer(K, h)
        P = I_KH @ P @ I_KH.T + r[i] * np.outer(K, K)
    return x, P


def test_gated_row_is_skipped_exactly(vehicle, dlc):
    """A 30 mm spike on d_fl (in range) fails the gate: the FL row alone is skipped."""
    kf = TwoStageKF(vehicle)
    row = 600
    spiked = with_values(dlc, row, d_fl=dlc.d[row, 0] + 0.030)
    estimate, covariances = kf.run_with_covariance(spiked)
    assert estimate.flags[row] & StepFlag.INNOVATION_GATED
    assert estimate.flags[row] & ROWS_SKIPPED == StepFlag.SUSPENSION_FL_SKIPPED
    dt = sample_intervals(spiked.t)[row]
    x, P = reference_step(
        kf, estimate.loads[row - 1], covariances[row - 1], spiked, row, dt, [1, 2, 3, 4, 5, 6]
    )
    np.testing.assert_allclose(estimate.loads[row], x, rtol=1e-9)
    np.testing.assert_allclose(covariances[row], P, rtol=1e-9)
    # The spike would otherwise move FL by hundreds of N more.
    unguarded = TwoStageKF(vehicle, guard_settings=GUARDS_OFF).run(spiked)
    error = abs(estimate.loads[row, 0] - dlc.reference[row, 0])
    assert abs(unguarded.loads[row, 0] - dlc.reference[row, 0]) > 300.0 + error


def test_gate_never_locks_the_data_out(vehicle, dlc):
    """Started 3 kN off with a confident covariance and a slow random walk, every row fails
    the gate at first: the rows are taken (released) within ``gate_release_time`` + one
    sample, and after 2 s the guarded filter is as good as the plain one (within 5 %)."""
    tuning = dataclasses.replace(vehicle.filter, initial_std=20.0, process_noise_density=1e5)
    slow = vehicle.replace(filter=tuning)
    late = dlc.t - dlc.t[0] > 2.0
    errors = {}
    for name, settings in (("guarded", None), ("plain", GUARDS_OFF)):
        kf = TwoStageKF(slow, guard_settings=settings)
        start = kf.initial_state()
        x0 = start.x + np.array([3000.0, -3000.0, 3000.0, -3000.0])
        estimate = kf.run(dlc, dataclasses.replace(start, x=x0))
        errors[name] = pooled_rmse(estimate.loads[late], dlc.reference[late])
        released = np.flatnonzero(estimate.flags & StepFlag.GATE_RELEASED)
        if settings is None:
            assert dlc.t[released[0]] - dlc.t[0] <= GuardSettings().gate_release_time + 0.011
    assert errors["guarded"] < 150.0
    assert errors["guarded"] <= 1.05 * errors["plain"]


def test_sigma_grows_across_a_gap(vehicle, dlc):
    """5 s and 1 h gaps: sigma after >= sigma before, and covers the error (issue: 176 -> 8.5 N)."""
    kf = TwoStageKF(vehicle)
    gap_at = 700
    for gap in (5.0, 3600.0):
        t = dlc.t.copy()
        t[gap_at:] += gap
        estimate = kf.run(dataclasses.replace(dlc, t=t))
        before, after = estimate.std[gap_at - 1], estimate.std[gap_at]
        assert np.all(after >= before)
        error = np.abs(estimate.loads[gap_at] - dlc.reference[gap_at])
        assert np.all(error <= 3.0 * after)
        weight = vehicle.mass.total * GRAVITY
        assert np.all(after <= weight)


@pytest.mark.parametrize(
    "tuning",
    [{"initial_std": 1e200}, {"initial_std": 1.2e6}, {"process_noise_density": 1e300}],
)
def test_extreme_tuning_never_breaks_the_filter(vehicle, dlc, tuning):
    """The covariance ceiling (m g)^2 and floor keep every step finite (issue 8, item 6)."""
    kf = TwoStageKF(vehicle.replace(filter=dataclasses.replace(vehicle.filter, **tuning)))
    estimate = kf.run(dlc)
    assert np.isfinite(estimate.loads).all() and np.isfinite(estimate.std).all()
    assert not np.any(estimate.flags & StepFlag.STEP_REJECTED)
    assert estimate.flags[0] & StepFlag.COVARIANCE_LIMITED
    # With q = 1e300 the filter follows the measurements alone: a few hundred N at worst.
    assert pooled_rmse(estimate.loads, dlc.reference) < 250.0
    state, sample = kf.initial_state(), Sample(d=dlc.d[0], v=dlc.v[0], acc=dlc.acc[0], vx=dlc.vx[0])
    state, one = kf.step(state, sample, 0.01)
    assert np.isfinite(one.loads).all() and np.all(np.diag(state.P) > 0)


def test_guard_settings_reject_bad_values():
    with pytest.raises(ValueError, match="innovation_gate"):
        GuardSettings(innovation_gate=0.0)
    with pytest.raises(ValueError, match="isolation_fraction"):
        GuardSettings(isolation_fraction=1.5)


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
