"""MHE on OSQP: equals the KF for N = 1, hard equilibrium, exact bounds, fallback."""

import dataclasses
import math

import numpy as np
import pytest

from wheelload.estimators import Sample, StepFlag
from wheelload.estimators.guards.settings import GUARDS_OFF
from wheelload.estimators.kf.projection import ProjectionKF
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import Arrival, Constraint, MheSettings, SolverSettings
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import ModelParameters
from wheelload.studies.bench.numpy_kf import pseudo_measurements
from wheelload.studies.drive.synthetic import SensorNoise, slalom, steady_cornering, synthetic_log
from wheelload.studies.experiments.equilibrium_residuals import paper_model

NOISE = SensorNoise(acceleration=0.05, travel=0.0003)
TIGHT = SolverSettings(eps_abs=1e-9, eps_rel=1e-9, polish=True, max_iter=20000)


@pytest.fixture(scope="module")
def drive(fixed_vehicle):
    return synthetic_log(
        fixed_vehicle, slalom(duration=3.0), noise=NOISE, spring_error=0.08, seed=5
    )


@pytest.fixture(scope="module")
def wheel_lift(fixed_vehicle):
    """A 15 m/s^2 left turn: the inner (left) wheels' linear loads go below zero."""
    manoeuvre = steady_cornering(ay=15.0, duration=3.0)
    return synthetic_log(fixed_vehicle, manoeuvre, noise=NOISE, spring_error=0.08, seed=6)


def right_hand_sides(vehicle, signals):
    p = ModelParameters.from_vehicle(vehicle).vector()
    return pseudo_measurements(signals, p)[2]  # b with the vehicle's model terms


def test_one_sample_soft_window_with_kalman_arrival_is_the_kf(fixed_vehicle, drive):
    settings = MheSettings(horizon=1, constraint=Constraint.SOFT, bounded=False, solver=TIGHT)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(drive)
    kf = TwoStageKF(fixed_vehicle).run(drive)
    assert not mhe.fallback.any()
    # solver tolerance 1e-9 in kN on 4 kN loads, with polishing: measured 1.4e-5 N
    np.testing.assert_allclose(mhe.loads, kf.loads, rtol=0, atol=1e-3)


def test_one_sample_hard_window_is_the_maximum_probability_projection(fixed_vehicle, drive):
    settings = MheSettings(horizon=1, constraint=Constraint.HARD, solver=TIGHT)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(drive)
    # the projection's guards off: its innovation gate rejects the roll row of two samples
    # (8 % spring error against the exact constraint's S = A P A^T); the hard window has none
    projected = ProjectionKF(fixed_vehicle, guard_settings=GUARDS_OFF).run(drive)
    np.testing.assert_allclose(mhe.loads, projected.loads, rtol=0, atol=1e-3)


def test_soft_unbounded_window_with_exact_arrival_keeps_the_kf_estimate(fixed_vehicle, drive):
    """Linear-Gaussian MHE with the Kalman arrival cost is the KF for any N."""
    mhe = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=10)).run(drive)
    kf = TwoStageKF(fixed_vehicle).run(drive)
    # default tolerances 1e-6 kN: a few tenths of a newton
    np.testing.assert_allclose(mhe.loads, kf.loads, rtol=0, atol=1.0)


@pytest.mark.parametrize("bounded", [False, True])
@pytest.mark.parametrize("arrival", list(Arrival))
def test_hard_window_satisfies_equilibrium_on_every_sample(
    fixed_vehicle, wheel_lift, bounded, arrival
):
    settings = MheSettings(horizon=10, constraint=Constraint.HARD, bounded=bounded, arrival=arrival)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(wheel_lift)
    b = right_hand_sides(fixed_vehicle, wheel_lift)
    feasible = ~mhe.fallback
    relative = np.abs(mhe.residual) / np.abs(b).max(axis=1, keepdims=True)
    assert feasible.mean() > 0.9
    assert relative[feasible].max() <= 1e-6


@pytest.mark.parametrize("constraint", list(Constraint))
def test_bounds_keep_every_load_at_or_above_zero(fixed_vehicle, wheel_lift, constraint):
    # The synthetic log obeys the paper's model exactly; the terms beyond it
    # (road frame, link loads) would be a model mismatch here.
    fixed_vehicle = paper_model(fixed_vehicle)
    assert TwoStageKF(fixed_vehicle).run(wheel_lift).loads.min() < -50.0  # the KF reports lift-off
    settings = MheSettings(horizon=10, constraint=constraint, bounded=True, max_load=2.0e4)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(wheel_lift)
    assert mhe.loads.min() >= 0.0  # exactly: in-tolerance violations are clipped
    assert mhe.loads.max() <= 2.0e4
    assert np.all(np.isfinite(mhe.loads))
    assert (mhe.loads.min(axis=1) == 0.0).sum() > 10  # the bound is active during lift-off


def test_iteration_cap_falls_back_to_the_kf_and_flags_it(fixed_vehicle, drive):
    # bounded: an unbounded window's QP is solved at its first iteration (qp.UNCONSTRAINED_SETTINGS)
    solver = SolverSettings(max_iter=1, check_termination=1)
    settings = MheSettings(horizon=5, bounded=True, solver=solver)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(drive)
    kf = TwoStageKF(fixed_vehicle).run(drive)
    capped = mhe.status != 1
    assert capped.any()
    assert np.array_equal(mhe.fallback, capped)
    np.testing.assert_array_equal(mhe.loads[capped], kf.loads[capped])
    frame = mhe.to_pandas()
    assert {"status", "solver_status", "iterations", "fallback", "solve_time"} <= set(frame.columns)


def test_settings_reject_bad_values():
    with pytest.raises(ValueError, match="horizon"):
        MheSettings(horizon=0)
    with pytest.raises(TypeError, match="Constraint"):
        MheSettings(constraint="hard")
    with pytest.raises(ValueError, match="max_load"):
        MheSettings(max_load=-1.0)
    with pytest.raises(TypeError):
        MheSettings(horizon=5, window=3)
    assert MheSettings().max_load == math.inf


@pytest.mark.parametrize("constraint", list(Constraint))
def test_step_equals_run_with_missing_inputs(fixed_vehicle, wheel_lift, constraint):
    d, acc = wheel_lift.d.copy(), wheel_lift.acc.copy()
    d[12, 1] = np.nan  # a travel sensor drops out: its suspension rows are skipped
    acc[20, 1] = np.inf  # a lateral acceleration glitch: the roll row is skipped
    signals = dataclasses.replace(wheel_lift, d=d, acc=acc).slice(0, 40)
    mhe = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(horizon=5, constraint=constraint, bounded=True)
    )
    whole = mhe.run(signals)
    dt = sample_intervals(signals.t)
    state = mhe.initial_state(float(np.median(dt)))
    for k in range(len(signals)):
        sample = Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=float(signals.vx[k]))
        state, one = mhe.step(state, sample, float(dt[k]))
        # the filter runs compiled in run and through CasADi in step: rounding only, carried
        # through the ADMM iterations to within the solver tolerance (1e-6 kN = 1e-3 N); 1e-2 N
        np.testing.assert_allclose(one.loads[0], whole.loads[k], rtol=0, atol=1e-2)
        assert one.flags[0] == whole.flags[k]
        assert one.status[0] == whole.status[k]
    assert whole.flags[12] != 0 and whole.flags[20] != 0
    assert np.all(np.isfinite(whole.loads))


def test_polishing_prints_nothing(fixed_vehicle, wheel_lift, capfd):
    for bounded in (False, True):
        settings = MheSettings(horizon=5, bounded=bounded, solver=TIGHT)
        MovingHorizonEstimator(fixed_vehicle, settings).run(wheel_lift.slice(0, 50))
    assert capfd.readouterr().out == ""


@pytest.mark.parametrize("dt", [0.0, -0.01, math.nan])
def test_invalid_interval_holds_the_estimate_and_solving_goes_on(fixed_vehicle, drive, dt):
    mhe = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=5))
    state = mhe.initial_state(0.01)
    samples = [Sample(d=drive.d[k], v=drive.v[k], acc=drive.acc[k], vx=drive.vx[k])
               for k in range(4)]  # fmt: skip
    state, first = mhe.step(state, samples[0], 0.01)
    held_state, held = mhe.step(state, samples[1], dt)
    assert held_state is state  # nothing solved, nothing changed
    np.testing.assert_array_equal(held.loads, first.loads)
    rejected = sum(StepFlag.update_flags()) | StepFlag.STEP_REJECTED  # not the input bits 20-22
    assert held.flags[0] == rejected and held.status[0] == 0
    assert np.isfinite(held.residual).all() and np.isfinite(held.std).all()
    for sample in samples[2:]:
        held_state, estimate = mhe.step(held_state, sample, 0.01)
        assert estimate.status[0] == 1 and np.isfinite(estimate.loads).all()


@pytest.mark.parametrize("constraint", list(Constraint))
def test_a_run_is_a_function_of_its_log_alone(fixed_vehicle, wheel_lift, constraint):
    """The same log twice on one estimator object: the same numbers, bit for bit."""
    mhe = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(horizon=8, constraint=constraint, bounded=True)
    )
    first = mhe.run(wheel_lift)
    mhe.run(wheel_lift.slice(100, 200))  # another log between the two runs
    second = mhe.run(wheel_lift)
    np.testing.assert_array_equal(second.loads, first.loads)
    np.testing.assert_array_equal(second.fallback, first.fallback)


@pytest.mark.parametrize("constraint", list(Constraint))
def test_without_any_input_the_estimate_is_held_and_sigma_grows(fixed_vehicle, constraint):
    """Every input missing for 20 s: no drift, no swing, sigma grows, recovery after."""
    signals = synthetic_log(fixed_vehicle, slalom(duration=24.0), noise=NOISE, seed=8)
    gap = slice(200, 2200)
    missing = {name: getattr(signals, name).copy() for name in ("d", "v", "acc", "vx")}
    for values in missing.values():
        values[gap] = np.nan
    signals = dataclasses.replace(signals, **missing)
    settings = MheSettings(horizon=10, constraint=constraint, bounded=True)
    estimate = MovingHorizonEstimator(fixed_vehicle, settings).run(signals)
    held = estimate.loads[gap]
    last = estimate.loads[gap.start - 1]
    # the first N gap samples still see data in the window; from then on the window has none
    assert np.all(held[settings.horizon :] == held[settings.horizon])  # exactly held
    # the random walk carries the last estimate: equal to the solver tolerance (measured 8e-3 N)
    assert np.abs(held - last).max() < 1.0
    assert not estimate.fallback.any() and np.all(estimate.status == 1)
    assert np.all(np.diff(estimate.std[gap], axis=0) >= 0.0)  # sigma never shrinks
    # the reported sigma's P term c_P sqrt(P): measured 797 N at the end against 137 N
    # (soft) and 147 N (hard) before, 5.8x and 5.4x
    assert estimate.std[gap.stop - 1].min() > 4 * estimate.std[gap.start - 1].max()
    after = slice(gap.stop + 100, None)  # one second after the gap: back on the reference
    error = np.abs(estimate.loads[after] - signals.reference[after]).max()
    assert error < 400.0  # measured 221 N (soft), 141 N (hard): the filter's usual error


@pytest.mark.parametrize("constraint", list(Constraint))
@pytest.mark.parametrize("bounded", [False, True])
def test_ring_buffer_window_equals_the_per_sample_state_path(fixed_vehicle, constraint, bounded):
    """``run``'s ring buffers (estimators/mhe/ring.py) against the MheState-per-sample loop.

    Same arithmetic and the same OSQP calls in the same order: bit-identical,
    with gaps in the travel and the IMU (closed-form held windows) and a lag.
    """
    import dataclasses

    from wheelload.estimators import read_log
    from wheelload.studies.pipeline.example_log import example_log_path

    signals = read_log(example_log_path()).slice(0, 300)
    d, acc = signals.d.copy(), signals.acc.copy()
    d[100:130, 1] = np.nan
    acc[150:200] = np.nan  # every equilibrium row and no suspension row... for 50 samples
    d[150:200] = np.nan  # ... nor travel: windows without data, held in closed form
    signals = dataclasses.replace(signals, d=d, acc=acc)
    # a few iterations only: unsolved windows fall back to the KF (and polish when bounded);
    # an unbounded window's first iteration is its minimiser (qp.UNCONSTRAINED_SETTINGS), to
    # sigma = 1e-6: a tolerance below that fails it
    starved = SolverSettings(max_iter=10, check_termination=1, polish=True)
    if not bounded:
        starved = SolverSettings(max_iter=2, check_termination=1, eps_abs=1e-14, eps_rel=1e-14)
    for lag, solver in ((0, SolverSettings()), (3, SolverSettings()), (0, starved)):
        settings = MheSettings(
            horizon=6, constraint=constraint, bounded=bounded, lag=lag, solver=solver
        )
        ring = MovingHorizonEstimator(fixed_vehicle, settings).run(signals)
        reference = MovingHorizonEstimator(fixed_vehicle, settings)
        reference.per_sample_states = True
        states = reference.run(signals)
        for name in ("loads", "std", "residual", "flags", "status", "iterations", "fallback"):
            np.testing.assert_array_equal(getattr(ring, name), getattr(states, name), err_msg=name)
        assert (ring.iterations == 0).sum() > 0  # the held windows were exercised
        if solver is starved:
            assert ring.fallback.sum() > 10  # the failed solves were exercised
