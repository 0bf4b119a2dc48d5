"""Hypothesis properties of the guarded filter over random logs with random faults.

- outputs finite, whatever the inputs (NaN, inf, 1e30, in-range spikes);
- the plausibility flags equal an independent numpy check of the ranges;
- every sample's state equals an independent numpy Kalman step that applies
  exactly the update rows the flags report as used (a guarded row changes
  nothing; tolerance 1e-9 relative, same arithmetic in another order);
- sigma after any gap is at least sigma before it (steady state, clean log).
"""

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from wheelload.estimators import StepFlag
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kf.tuning import nominal_interval, with_filter_sigma
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import GRAVITY, equilibrium_function, gates_function, suspension_function
from wheelload.models.roll_split import SPLIT_NOISE_RATIO, roll_split_function
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

N = 300
HYPOTHESIS = settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


@pytest.fixture(scope="module")
def base(fixed_vehicle):
    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    return synthetic_log(
        fixed_vehicle, slalom(duration=N / 100), noise=noise, spring_error=0.1, seed=4
    )


@pytest.fixture(scope="module")
def kf(fixed_vehicle):
    """The step's properties, sample by sample: no whole-log file check before the run (a
    hostile log's warp would take a travel zero off)."""
    return TwoStageKF(fixed_vehicle, check_file=False)


@pytest.fixture(scope="module")
def model(kf):
    """The model's gates, suspension and equilibrium functions mapped over N samples, and
    the roll-split row, built once for every example."""
    maps = [f().map(N) for f in (gates_function, suspension_function, equilibrium_function)]
    split = np.asarray(roll_split_function()(kf.p)).ravel()
    return maps, split


@pytest.fixture(scope="module")
def own_sigma_kf(fixed_vehicle):
    """The KF reporting its own sigma, sqrt(P_ii)."""
    kf = TwoStageKF(fixed_vehicle)
    kf.tuning = with_filter_sigma(kf.tuning)
    return kf


values = st.one_of(
    st.sampled_from([np.nan, np.inf, -np.inf, 1e30, -1e30, 50.0, 100.0, 0.29, -0.29]),
    st.floats(-0.05, 0.05),  # in-range travel-sized offsets
    st.floats(-20.0, 20.0),  # in-range acceleration-sized offsets
)
faults = st.lists(
    st.tuples(st.integers(1, N - 1), st.integers(0, 11), values, st.booleans()), max_size=25
)


def with_faults(signals, faults):
    """Each fault (row, channel, value, replace): set or add ``value`` at one sample."""
    u = input_matrix(signals).T.copy()
    for row, channel, value, replace in faults:
        u[row, channel] = value if replace or not np.isfinite(value) else u[row, channel] + value
    return dataclasses.replace(
        signals, d=u[:, 0:4], v=u[:, 4:8], acc=u[:, 8:11], vx=u[:, 11].copy()
    )


def in_range(vehicle, u):
    """Independent range check of issue 8's plausibility (numpy, from the vehicle file)."""
    g = GuardSettings()
    weight = vehicle.mass.total * GRAVITY
    springs = np.array(
        [vehicle.suspension.front.spring_rate] * 2 + [vehicle.suspension.rear.spring_rate] * 2
    )
    ok = np.ones_like(u, dtype=bool)
    ok[:, 0:4] = np.abs(u[:, 0:4]) <= g.travel_range * weight / springs
    ok[:, 4:8] = np.abs(u[:, 4:8]) <= g.max_travel_rate
    ok[:, 8:11] = np.abs(u[:, 8:11]) <= g.max_acceleration * GRAVITY
    ok[:, 11] = np.abs(u[:, 11]) <= g.max_speed
    return ok | ~np.isfinite(u)  # a missing value is missing, not implausible


def held(u, valid, dt, hold_time):
    """Independent numpy hold: a missing or implausible input takes its last valid value
    while less than ``hold_time`` has passed since (``GuardSettings.hold_time``)."""
    value, credit = np.zeros(u.shape[1]), np.zeros(u.shape[1])
    u_term, valid_term = np.zeros_like(u), np.zeros_like(valid)
    for k in range(u.shape[0]):
        left = credit - dt[k]
        hold = ~valid[k] & (left > 0)
        u_term[k] = np.where(valid[k], u[k], np.where(hold, value, 0.0))
        valid_term[k] = valid[k] | hold
        value = np.where(valid[k], u[k], value)
        credit = np.where(valid[k], hold_time, np.maximum(left, 0.0))
    return u_term, valid_term


def measurements(vehicle, kf, model, u, dt):
    """z (n, 4), A (n, 3, 4), b (n, 3); a missing or implausible input enters the model
    terms it feeds with its last valid value for the hold time, then as 0 with those
    terms gated off, as in the filter (the rows it feeds are unused)."""
    valid = np.isfinite(u) & in_range(vehicle, np.where(np.isfinite(u), u, 0.0))
    u, valid = held(np.where(valid, u, 0.0), valid, dt, GuardSettings().hold_time)
    u, valid = u.T, valid.T
    n = u.shape[1]
    (gates_map, suspension_map, equilibrium_map), _ = model
    gates = gates_map(valid.astype(float), kf.p)[0]
    z = np.asarray(suspension_map(u, gates, kf.p)).T
    A, b = equilibrium_map(u, gates, kf.p)
    return z, np.asarray(A).reshape(3, n, 4).transpose(1, 0, 2), np.asarray(b).T


def reference_step(numpy_step, kf, split, x, P, z, A, b, dt, nominal, rows):
    """Numpy step: predict, then the scalar updates of ``rows`` (0-6) only, and the
    roll-split row (y = 0, noise SPLIT_NOISE_RATIO x the roll row's) when no travel row
    is used but the roll row is (the IMU-only mode of models/roll_split.py)."""
    q, r_s, r_c = kf.tuning[0], kf.tuning[1], kf.tuning[2:5]
    H, y_all = np.vstack([np.eye(4), A, split]), np.concatenate([z, b, [0.0]])
    r = np.concatenate([np.full(4, r_s), r_c, [SPLIT_NOISE_RATIO * r_c[2]]]) / nominal
    if 6 in rows and not set(rows) & {0, 1, 2, 3}:
        rows = [*rows, 7]
    return numpy_step(x, P, q, dt, H, y_all, r, rows)


#: Three travel sensors (d and v of FR, RL, RR) lost for 0.1 s while FL still reads: the
#: weak roll-split row stays off (it observes the warp only when no travel row is used).
ONE_TRAVEL_LEFT = [(row, channel, np.nan, True) for row in range(150, 160)
                   for channel in (1, 2, 3, 5, 6, 7)]  # fmt: skip


@HYPOTHESIS
@given(faults=faults)
@example(faults=ONE_TRAVEL_LEFT)
def test_guarded_filter_is_finite_flags_exact_and_skips_rows_exactly(
    fixed_vehicle, base, kf, model, numpy_step, faults
):
    signals = with_faults(base, faults)
    estimate, P = kf.run_with_covariance(signals)
    assert np.isfinite(estimate.loads).all() and np.isfinite(estimate.std).all()
    assert np.isfinite(estimate.residual).all() and np.isfinite(P).all()
    assert np.all(np.diagonal(P, axis1=1, axis2=2) > 0)
    # Plausibility flags, channel group by channel group.
    u = input_matrix(signals).T
    bad = ~in_range(fixed_vehicle, u)
    flags = estimate.flags
    np.testing.assert_array_equal(flags & StepFlag.TRAVEL_IMPLAUSIBLE != 0, bad[:, 0:8].any(1))
    np.testing.assert_array_equal(
        flags & StepFlag.ACCELERATION_IMPLAUSIBLE != 0, bad[:, 8:11].any(1)
    )
    np.testing.assert_array_equal(flags & StepFlag.SPEED_IMPLAUSIBLE != 0, bad[:, 11])
    assert not np.any(flags & StepFlag.STEP_REJECTED)
    # Each sample's state is the numpy step with exactly the used rows.
    dt, nominal = sample_intervals(signals.t), nominal_interval(signals.t)
    z, A, b = measurements(fixed_vehicle, kf, model, u, dt)
    skipped = [flag.value for flag in StepFlag.update_flags()]
    for k in range(1, len(signals)):
        rows = [i for i in range(7) if not flags[k] & skipped[i]]
        x, P_k = reference_step(
            numpy_step,
            kf,
            model[1],
            estimate.loads[k - 1],
            P[k - 1],
            z[k],
            A[k],
            b[k],
            dt[k],
            nominal,
            rows,
        )
        np.testing.assert_allclose(estimate.loads[k], x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(P[k], P_k, rtol=1e-8, atol=1e-6)
        if not rows:
            np.testing.assert_array_equal(estimate.loads[k], estimate.loads[k - 1])


@HYPOTHESIS
@given(at=st.integers(100, N - 1), gap=st.floats(0.02, 3600.0))
def test_sigma_after_any_gap_at_least_sigma_before(base, own_sigma_kf, at, gap):
    """The filter's own sigma, sqrt(P_ii) (the reported sigma's covariance term)."""
    t = base.t.copy()
    t[at:] += gap
    estimate = own_sigma_kf.run(dataclasses.replace(base, t=t))
    assert np.all(estimate.std[at] >= estimate.std[at - 1])
