"""Covariance limits on a plant log: sigma grows across a gap, extreme tuning stays finite.

The log is the ISO lane change simulated by the full-vehicle plant with the
standard sensor models (``run_scenario``, fixture ``dlc``); the reference loads are the
plant's.
"""

import dataclasses

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelload.estimators import Sample, StepFlag
from wheelload.estimators.guards import limits
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kf.tuning import with_filter_sigma
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import GRAVITY
from wheelload.studies.experiments.faults.fault_injection import pooled_rmse


def test_sigma_grows_across_a_gap(vehicle, dlc):
    """5 s and 1 h gaps: the filter's own sigma (sqrt P) after >= before, and covers the error
    (issue: 176 -> 8.5 N); the reported sigma stays finite and within the weight."""
    kf = TwoStageKF(vehicle)
    kf.tuning = with_filter_sigma(kf.tuning)
    reported = TwoStageKF(vehicle)
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
        sigma = reported.run(dataclasses.replace(dlc, t=t)).std
        assert np.all(np.isfinite(sigma)) and np.all((sigma >= 0) & (sigma <= weight))


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


# --- the envelope and the ceiling as properties of the step's limit functions ----------

WEIGHT = 1650.0 * GRAVITY
LIMITS = GuardSettings()


def numeric(function, *arguments):
    """``function`` of CasADi symbols evaluated at numeric arguments (a Function of them)."""
    symbols = [ca.SX.sym(f"a{k}", *np.shape(a)) if np.ndim(a) else ca.SX.sym(f"a{k}")
               for k, a in enumerate(arguments)]  # fmt: skip
    outputs = function(*symbols)
    outputs = outputs if isinstance(outputs, tuple) else (outputs,)
    evaluate = ca.Function("f", symbols, list(outputs))
    values = evaluate(*[ca.DM(np.asarray(a, dtype=float)) for a in arguments])
    values = values if isinstance(values, (list, tuple)) else [values]
    return [np.asarray(v) for v in values]


def within_envelope(x, x_prior, total):
    """Independent reading of the envelope (estimators/guards/limits.py): every |F_z| within
    load_limit m g and the total no further outside the log's vertical-row range, widened
    by total_margin m g, than before the update."""
    low = WEIGHT + total[0] - LIMITS.total_margin * WEIGHT
    high = WEIGHT + total[1] + LIMITS.total_margin * WEIGHT
    excess = lambda value: max(value - high, low - value, 0.0)  # noqa: E731
    bounded = np.all(np.abs(x) <= LIMITS.load_limit * WEIGHT)
    return bool(bounded and excess(np.sum(x)) <= excess(np.sum(x_prior)))


loads = st.lists(st.floats(-6 * WEIGHT, 6 * WEIGHT), min_size=4, max_size=4)


@settings(max_examples=200, deadline=None)
@given(x=loads, x_prior=loads, low=st.floats(-WEIGHT, 0.0), high=st.floats(0.0, WEIGHT))
def test_load_envelope_is_two_sided_and_equals_its_definition(x, x_prior, low, high):
    """Exact agreement (a boolean) on random updates, two to six m g either side."""
    (ok,) = numeric(lambda a, b, t: limits.within_load_limit(a, b, t, WEIGHT, LIMITS),
                    np.array(x), np.array(x_prior), np.array([low, high]))  # fmt: skip
    assert bool(ok) == within_envelope(np.array(x), np.array(x_prior), (low, high))


def test_a_huge_negative_load_is_outside_the_envelope():
    static = np.full(4, WEIGHT / 4)
    for wheel in range(4):
        x = static.copy()
        x[wheel] = -4.0 * WEIGHT
        x[(wheel + 1) % 4] += 5.0 * WEIGHT  # the total unchanged: only the bound can refuse
        (ok,) = numeric(lambda a, b, t: limits.within_load_limit(a, b, t, WEIGHT, LIMITS),
                        x, static, np.zeros(2))  # fmt: skip
        assert not bool(ok), wheel


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), over=st.lists(st.booleans(), min_size=4, max_size=4))
def test_covariance_ceiling_keeps_p_positive_semidefinite_and_its_correlations(seed, over):
    """A random covariance with some variances far above the ceiling (m g)^2: the limited
    P has its diagonal in [floor^2, ceiling], stays symmetric positive semidefinite, and
    keeps every correlation coefficient (the ceiling scales row and column, D P D).
    Tolerances 1e-9 relative: a few products and one square root per entry."""
    rng = np.random.default_rng(seed)
    ceiling = WEIGHT**2
    root = rng.normal(size=(4, 4))
    P = root @ root.T + 0.1 * np.eye(4)
    scale = np.where(over, rng.uniform(2.0, 1e3, 4) * WEIGHT, rng.uniform(10.0, 0.5 * WEIGHT, 4))
    P = P / np.sqrt(np.outer(np.diag(P), np.diag(P))) * np.outer(scale, scale)
    limited, changed = numeric(lambda a: limits.limit_covariance(a, 1.0, ceiling), P)
    diagonal = np.diag(limited)
    assert np.all(diagonal <= ceiling * (1 + 1e-12)) and np.all(diagonal >= 1.0)
    np.testing.assert_allclose(diagonal, np.minimum(np.diag(P), ceiling), rtol=1e-12)
    np.testing.assert_allclose(limited, limited.T, rtol=0, atol=1e-12 * ceiling)
    assert np.linalg.eigvalsh(limited).min() >= -1e-9 * ceiling
    correlation = lambda M: M / np.sqrt(np.outer(np.diag(M), np.diag(M)))  # noqa: E731
    np.testing.assert_allclose(correlation(limited), correlation(P), rtol=1e-9, atol=1e-12)
    assert bool(changed) == any(over)


@pytest.mark.parametrize("floor", [0.3, 1.0, 7.0])
def test_covariance_floor_raises_small_variances_to_its_square(floor):
    """floor_covariance and limit_covariance with a floor of ``floor`` N: a variance below
    floor^2 becomes floor^2 (off-diagonals kept), one above is kept, and the flag says
    which happened; exact."""
    P = np.diag([0.25 * floor**2, 4.0 * floor**2, 0.5 * floor**2, 1e4])
    P[0, 3] = P[3, 0] = 0.1 * floor
    expected = P.copy()
    expected[0, 0] = expected[2, 2] = floor**2
    for limit in (lambda a: limits.floor_covariance(a, floor),
                  lambda a: limits.limit_covariance(a, floor, WEIGHT**2)):  # fmt: skip
        limited, changed = numeric(limit, P)
        np.testing.assert_array_equal(limited, expected)
        assert bool(changed)
        _, unchanged = numeric(limit, np.diag([2.0 * floor**2] * 3 + [1e4]))
        assert not bool(unchanged)


def test_an_update_that_brings_the_total_back_is_taken(vehicle, dlc):
    """A running filter whose loads sum to 0.5 m g too much (each wheel 2 kN high, P wide
    enough for every row to pass the gate): the first update takes the total back towards
    the vertical row's m a_z (the envelope refuses only updates that carry the total
    further out, estimators/guards/limits.py), to within 10 % of where it was."""
    from wheelload.estimators.guards.monitor_state import STARTED

    kf = TwoStageKF(vehicle)
    start = kf.initial_state()
    m = start.m.copy()
    m[STARTED] = 1
    weight = vehicle.mass.total * GRAVITY
    state = dataclasses.replace(start, x=start.x + 0.125 * weight, P=np.eye(4) * 1e8, m=m)
    sample = Sample(d=dlc.d[0], v=dlc.v[0], acc=dlc.acc[0], vx=dlc.vx[0])
    after, estimate = kf.step(state, sample, 0.01)
    before_off = abs(state.x.sum() - weight)
    assert before_off == pytest.approx(0.5 * weight)
    assert abs(after.x.sum() - dlc.acc[0, 2] * vehicle.mass.total) < 0.1 * before_off
    assert not estimate.flags & StepFlag.update_flags()[0]  # the FL row was taken


def running(kf, signals, samples):
    """``kf``'s state after the first ``samples`` samples of ``signals``, step by step."""
    state, dt = kf.initial_state(), np.diff(signals.t)
    for k in range(samples):
        sample = Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=signals.vx[k])
        state, _ = kf.step(state, sample, dt[k - 1] if k else 0.01)
    return state


@pytest.mark.parametrize("travel", [0.040, -0.040])
def test_an_update_that_carries_the_total_out_is_refused(vehicle, dlc, travel):
    """A running filter (the lane change's first 200 samples seen, so the vertical row's
    range is the log's own) meets 40 mm of travel on every wheel that the IMU does not
    see, with P wide enough for every row to pass the gate: the update would move the
    total by +0.85 or -0.66 m g (measured with the margin lifted), beyond the range
    widened by total_margin (0.25 m g), so it is not taken: the loads are the prediction,
    every row is flagged skipped and LOAD_LIMITED is set; a tenth of that travel (the
    total moved by 0.04 m g) is taken."""
    kf = TwoStageKF(vehicle)
    state, dt = running(kf, dlc, 200), np.diff(dlc.t)
    wide = dataclasses.replace(state, P=np.eye(4) * 1e8)
    k = 200
    sample = Sample(d=dlc.d[k] + travel, v=dlc.v[k], acc=dlc.acc[k], vx=dlc.vx[k])
    after, estimate = kf.step(wide, sample, dt[k - 1])
    np.testing.assert_array_equal(after.x, wide.x)
    skipped = sum(StepFlag.update_flags()[:7])
    assert estimate.flags[0] & skipped == skipped
    assert estimate.flags[0] & StepFlag.LOAD_LIMITED
    small = Sample(d=dlc.d[k] + 0.1 * travel, v=dlc.v[k], acc=dlc.acc[k], vx=dlc.vx[k])
    _, taken = kf.step(wide, small, dt[k - 1])
    assert not taken.flags[0] & (skipped | StepFlag.LOAD_LIMITED)


def test_the_vertical_rows_range_grows_without_ax(vehicle, dlc):
    """The envelope's range of the vertical row (its b less the weight, carried in the
    monitor state) takes a sample whose az reads 2 m/s^2 high whether or not ax is there
    (the vertical row needs az, not ax; the pitch row needs both): with ax missing it
    grows to within 1 % of where it grows with ax, about 2 m (aerodynamic lift aside)."""
    from wheelload.estimators.guards.monitor_state import TOTAL

    kf = TwoStageKF(vehicle)
    state, dt = running(kf, dlc, 100), np.diff(dlc.t)
    high = {}
    for name, ax in (("with ax", dlc.acc[100, 0]), ("without ax", np.nan)):
        acc = np.array([ax, dlc.acc[100, 1], GRAVITY + 2.0])
        after, _ = kf.step(state, Sample(d=dlc.d[100], v=dlc.v[100], acc=acc, vx=dlc.vx[100]),
                           dt[99])  # fmt: skip
        high[name] = after.m[TOTAL][1]
    assert high["with ax"] == pytest.approx(2.0 * vehicle.mass.total, rel=0.1)
    assert high["without ax"] == pytest.approx(high["with ax"], rel=0.01)
