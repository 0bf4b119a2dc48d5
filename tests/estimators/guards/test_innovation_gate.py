"""The innovation gate on a plant log: a gated row is skipped exactly, and never locks data out.

The log is the ISO lane change simulated by the full-vehicle plant with the
standard sensor models (``run_scenario``, fixture ``dlc``); the reference loads are the
plant's. Exactness checks compare with an independent numpy Kalman filter
(tolerance 1e-9 relative: same arithmetic in another order).
"""

import dataclasses

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators import StepFlag
from wheelload.estimators.guards.innovation_gate import gate_rows, prior_failures, prior_innovations
from wheelload.estimators.guards.monitor_state import STARTED
from wheelload.estimators.guards.settings import GUARDS_OFF, GuardSettings
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import equilibrium_function, gates_function, suspension_function
from wheelload.studies.experiments.faults.fault_injection import pooled_rmse

ROWS_SKIPPED = sum(StepFlag.update_flags())


def reference_step(numpy_step, kf, x, P, signals, k, dt, rows):
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
    return numpy_step(x, P, q, dt, H, y_all, r, rows)


def test_gated_row_is_skipped_exactly(fixed_vehicle, dlc, numpy_step, with_values):
    """A 30 mm spike on d_fl (in range) fails the gate: the FL row alone is skipped."""
    kf = TwoStageKF(fixed_vehicle)
    row = 600
    spiked = with_values(dlc, row, d_fl=dlc.d[row, 0] + 0.030)
    estimate, covariances = kf.run_with_covariance(spiked)
    assert estimate.flags[row] & StepFlag.INNOVATION_GATED
    assert estimate.flags[row] & ROWS_SKIPPED == StepFlag.SUSPENSION_FL_SKIPPED
    # Every input present and no update refused by the envelope: a row is skipped exactly
    # where the gate flags one, and that is rare on a clean plant log.
    gated = (estimate.flags & StepFlag.INNOVATION_GATED) != 0
    np.testing.assert_array_equal(gated, (estimate.flags & ROWS_SKIPPED) != 0)
    assert gated.mean() < 0.05
    dt = sample_intervals(spiked.t)[row]
    previous = estimate.loads[row - 1], covariances[row - 1]
    x, P = reference_step(numpy_step, kf, *previous, spiked, row, dt, [1, 2, 3, 4, 5, 6])
    np.testing.assert_allclose(estimate.loads[row], x, rtol=1e-9)
    np.testing.assert_allclose(covariances[row], P, rtol=1e-9)
    # The spike would otherwise move FL by hundreds of N more.
    unguarded = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF).run(spiked)
    error = abs(estimate.loads[row, 0] - dlc.reference[row, 0])
    assert abs(unguarded.loads[row, 0] - dlc.reference[row, 0]) > 300.0 + error


def test_gate_never_locks_the_data_out(fixed_vehicle, dlc):
    """Started 3 kN off with a confident covariance and a slow random walk, every row fails
    the gate at first: the rows are taken (released) within ``gate_release_time`` + one
    sample, and after 2 s the guarded filter is as good as the plain one (within 5 %)."""
    tuning = dataclasses.replace(fixed_vehicle.filter, initial_std=20.0, process_noise_density=1e5)
    slow = fixed_vehicle.replace(filter=tuning)
    late = dlc.t - dlc.t[0] > 2.0
    errors = {}
    for name, settings in (("guarded", None), ("plain", GUARDS_OFF)):
        kf = TwoStageKF(slow, guard_settings=settings)
        start = kf.initial_state()
        x0 = start.x + np.array([3000.0, -3000.0, 3000.0, -3000.0])
        m = start.m.copy()
        m[STARTED] = 1  # a running filter's state (a fresh one takes no prior on sample 0)
        estimate = kf.run(dlc, dataclasses.replace(start, x=x0, m=m))
        errors[name] = pooled_rmse(estimate.loads[late], dlc.reference[late])
        released = np.flatnonzero(estimate.flags & StepFlag.GATE_RELEASED)
        if settings is None:
            assert dlc.t[released[0]] - dlc.t[0] <= GuardSettings().gate_release_time + 0.011
    assert errors["guarded"] < 150.0
    assert errors["guarded"] <= 1.05 * errors["plain"]


def rule(passes, reject_time, other_group_failed, count):
    """The gate's release rule, read from its docstring: a row is taken when it passes, or
    has failed for gate_release_time, or rows of the other group fail too (for an
    equilibrium row also a suspension row earlier in the sample), or at least three rows
    fail against the prediction (a transient, not a sensor)."""
    released = reject_time >= GuardSettings().gate_release_time or other_group_failed
    return passes or released or count >= 3


@pytest.mark.parametrize("count", range(8))
@pytest.mark.parametrize("groups", [(0, 0), (1, 0), (0, 1), (1, 1)], ids=str)
def test_gate_transient_rule_on_constructed_failures(count, groups):
    """Every row of a sample against a constructed prior -- which groups failed, how many
    rows -- with the suspension rows passing (y = 0) or failing (y = 10 sigma), the
    equilibrium rows failing, and each row failing before for 0, half or all of the
    release time: taken exactly where the rule says. Exact (0/1)."""
    g = GuardSettings()
    suspension_prior, constraint_prior = groups
    for reject_time in (0.0, 0.5 * g.gate_release_time, g.gate_release_time):
        for suspension_fails in (False, True):
            gate, _ = gate_rows(ca.DM(np.full(7, reject_time)), ca.DM.zeros(7), g,
                                (suspension_prior, constraint_prior, count))  # fmt: skip
            for i in range(7):
                fails = suspension_fails if i < 4 else True
                taken = float(gate(i, 10.0 if fails else 0.0, 1.0))
                other = constraint_prior if i < 4 else (suspension_prior or suspension_fails)
                expected = rule(not fails, reject_time, other, count)
                assert taken == float(expected), (i, reject_time, suspension_fails)


@pytest.mark.parametrize("failing", [(), (0,), (2, 3), (4,), (5, 6), (1, 4, 6), tuple(range(7))])
def test_prior_failures_name_the_groups_and_count_the_rows(failing):
    """Rows failing against the prediction (y = 10 sigma) among rows that pass (y = 0),
    with one further failing row absent (available = 0, not counted): which group failed
    and how many rows, exactly."""
    y = np.array([10.0 if i in failing else 0.0 for i in range(7)])
    available = np.ones(7)
    absent = next((i for i in range(7) if i not in failing), None)
    if absent is not None:
        y[absent], available[absent] = 10.0, 0.0
    suspension, constraint, count = prior_failures(
        ca.DM(y), ca.DM.ones(7), ca.DM(available), ca.DM.zeros(7), GuardSettings()
    )
    assert float(suspension) == float(any(i < 4 for i in failing))
    assert float(constraint) == float(any(i >= 4 for i in failing))
    assert float(count) == len(failing)


def test_prior_innovations_of_each_row_against_numpy():
    """y = [z; b] - H x and S_ii = h_i P h_i^T + r_i with H = [I; A], numpy, on a P far
    from diagonal and noise variances of very different size per row (a swap of any two
    would show). Tolerance 1e-12 relative."""
    rng = np.random.default_rng(11)
    A = np.vstack([np.ones(4), [1.2, 1.2, -1.5, -1.5], [0.8, -0.8, 0.79, -0.79]])
    root = rng.normal(size=(4, 4)) * 100.0
    P = root @ root.T
    x, z, b = rng.uniform(3000, 5000, 4), rng.uniform(3000, 5000, 4), rng.normal(size=3) * 1e4
    r_s, r_c = np.array([1e2, 2e3, 3e4, 4e5]), np.array([5e6, 6e7, 7e8])
    y, S = (np.asarray(v).ravel() for v in prior_innovations(
        ca.DM(x), ca.DM(P), ca.DM(z), ca.DM(b), ca.DM(A), ca.DM(r_s), ca.DM(r_c)))  # fmt: skip
    H = np.vstack([np.eye(4), A])
    np.testing.assert_allclose(y, np.concatenate([z, b]) - H @ x, rtol=1e-12)
    expected = np.einsum("ij,jk,ik->i", H, P, H) + np.concatenate([r_s, r_c])
    np.testing.assert_allclose(S, expected, rtol=1e-12)
