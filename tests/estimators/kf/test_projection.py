"""Projection KF (Simon & Chia 2002): exact constraint, the Rc -> 0 limit of the KF, step = run."""

import dataclasses

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelload.estimators import Sample
from wheelload.estimators.kf.projection import (
    ProjectionKF,
    Weighting,
    project,
    projection_update,
)
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.result import StepFlag
from wheelload.models import GATES, INPUTS, ModelParameters, equilibrium_function
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

NOISE = SensorNoise(acceleration=0.05, travel=0.0003)


@pytest.fixture(scope="module")
def drive(vehicle):
    return synthetic_log(vehicle, slalom(duration=4.0), noise=NOISE, spring_error=0.08, seed=3)


def equilibrium_matrix(vehicle):
    p = ModelParameters.from_vehicle(vehicle).vector()
    A, _ = equilibrium_function()(np.zeros(len(INPUTS)), np.zeros(len(GATES)), p)
    return np.asarray(A)


@pytest.mark.parametrize("weighting", list(Weighting))
def test_projected_estimate_satisfies_equilibrium(vehicle, drive, weighting):
    estimate = ProjectionKF(vehicle, weighting=weighting).run(drive)
    b = estimate.residual + estimate.loads @ equilibrium_matrix(vehicle).T
    # exact projection on every row taken (a gated row is not projected on): only rounding
    # of 1e4-sized numbers remains
    skipped = [StepFlag.VERTICAL_SKIPPED, StepFlag.PITCH_SKIPPED, StepFlag.ROLL_SKIPPED]
    taken = np.column_stack([estimate.flags & flag == 0 for flag in skipped])
    assert taken.mean() > 0.99
    bound = 1e-12 * np.abs(b).max(axis=1, keepdims=True)
    assert np.all((np.abs(estimate.residual) <= bound) | ~taken)
    assert np.all(np.isfinite(estimate.std))


def test_kf_approaches_maximum_probability_projection_as_rc_vanishes(vehicle, drive):
    projected = ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY).run(drive)
    errors = []
    for density in (1e-2, 1e-4, 1e-6):
        tuning = dataclasses.replace(vehicle.filter, constraint_noise_density=(density,) * 3)
        kf = TwoStageKF(vehicle.replace(filter=tuning)).run(drive)
        errors.append(np.abs(kf.loads - projected.loads).max())
    # the gap is first order in Rc: a hundredfold smaller Rc, a hundredfold smaller gap
    assert errors[1] < errors[0] / 50 and errors[2] < errors[1] / 50
    assert errors[2] < 1e-5


def test_weightings_agree_with_isotropic_tuning_and_differ_with_a_sensor_lost(vehicle, drive):
    """Isotropic Q, Rs, P0 keep P = a I + c n n^T (n: null vector of A), so P A^T = a A^T
    and W = P^-1 projects like W = I; a missing travel channel breaks the isotropy."""
    ml = ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY).run(drive)
    ls = ProjectionKF(vehicle, weighting=Weighting.LEAST_SQUARES).run(drive)
    np.testing.assert_allclose(ml.loads, ls.loads, rtol=0, atol=1e-6)
    d, v = drive.d.copy(), drive.v.copy()
    d[100:200, 0] = np.nan
    v[100:200, 0] = np.nan
    lost = dataclasses.replace(drive, d=d, v=v)
    ml = ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY).run(lost)
    ls = ProjectionKF(vehicle, weighting=Weighting.LEAST_SQUARES).run(lost)
    assert np.abs(ml.loads - ls.loads)[100:200].max() > 1.0
    assert np.all(np.isfinite(ml.loads)) and np.all(np.isfinite(ls.loads))


@pytest.mark.parametrize("weighting", list(Weighting))
def test_step_equals_run(vehicle, drive, weighting):
    kf = ProjectionKF(vehicle, weighting=weighting)
    whole = kf.run(drive.slice(0, 60))
    state = kf.initial_state()
    dt = sample_intervals(drive.t[:60])
    for k in range(60):
        sample = Sample(d=drive.d[k], v=drive.v[k], acc=drive.acc[k], vx=float(drive.vx[k]))
        state, one = kf.step(state, sample, float(dt[k]))
        np.testing.assert_allclose(one.loads[0], whole.loads[k], rtol=0, atol=1e-8)


def test_weighting_must_be_an_enum(vehicle):
    with pytest.raises(TypeError, match="Weighting"):
        ProjectionKF(vehicle, weighting="P^-1")


def _numeric_projection(x, P, A, b, W_inv):
    xs, Ps = (ca.SX.sym(name, *shape) for name, shape in (("x", (4, 1)), ("P", (4, 4))))
    W = Ps if W_inv is None else ca.DM(W_inv)
    f = ca.Function("f", [xs, Ps], list(project(xs, Ps, ca.DM(A), ca.DM(b), W)))
    return (np.asarray(out) for out in f(x, P))


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    weighting=st.sampled_from(list(Weighting)),
)
def test_projection_invariants(vehicle, seed, weighting):
    """A x = b after projection, P stays symmetric PSD, and (W = P^-1) A P = 0."""
    rng = np.random.default_rng(seed)
    A = equilibrium_matrix(vehicle)
    root = rng.normal(size=(4, 4)) * rng.uniform(10, 500)
    P = root @ root.T + np.eye(4)
    x = rng.uniform(2000, 6000, size=4)
    b = A @ rng.uniform(2000, 6000, size=4)
    W_inv = None if weighting is Weighting.MAXIMUM_PROBABILITY else np.eye(4)
    x_new, P_new = _numeric_projection(x, P, A, b, W_inv)
    assert np.abs(A @ x_new.ravel() - b).max() <= 1e-9 * np.abs(b).max()
    np.testing.assert_allclose(P_new, P_new.T, rtol=0, atol=1e-12 * np.abs(P).max())
    assert np.linalg.eigvalsh(P_new).min() >= -1e-9 * np.abs(P).max()
    if weighting is Weighting.MAXIMUM_PROBABILITY:
        assert np.abs(A @ P_new).max() <= 1e-8 * np.abs(A).max() * np.abs(P).max()


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_each_weighting_is_its_closed_form_projection(vehicle, seed):
    """The filter's second stage against the closed forms (Simon & Chia eq. 9, 35), numpy:
    W = P^-1 gives x + P A^T (A P A^T)^-1 (b - A x) and W = I gives
    x + A^T (A A^T)^-1 (b - A x). Tolerance 1e-9 relative to the loads (about 6e-6 N);
    with a P far from isotropic the two differ by more than 1e-3 N (at least 0.015 N over
    20 000 draws), so swapping them cannot pass."""
    rng = np.random.default_rng(seed)
    A = equilibrium_matrix(vehicle)
    root = rng.normal(size=(4, 4)) * np.array([10.0, 40.0, 160.0, 640.0])
    P = root @ root.T + np.eye(4)
    x = rng.uniform(2000, 6000, size=4)
    b = A @ (x + rng.normal(size=4) * 300.0)
    closed = {
        Weighting.MAXIMUM_PROBABILITY: x + P @ A.T @ np.linalg.solve(A @ P @ A.T, b - A @ x),
        Weighting.LEAST_SQUARES: x + A.T @ np.linalg.solve(A @ A.T, b - A @ x),
    }
    difference = closed[Weighting.MAXIMUM_PROBABILITY] - closed[Weighting.LEAST_SQUARES]
    assert np.abs(difference).max() > 1e-3
    xs, Ps = ca.SX.sym("x", 4), ca.SX.sym("P", 4, 4)
    for weighting, expected in closed.items():
        update = projection_update(weighting)
        x_new, P_new, *_ = update(xs, Ps, ca.DM(b), ca.DM(A), ca.DM.zeros(3), ca.DM.ones(3))
        f = ca.Function("stage", [xs, Ps], [x_new, P_new])
        got, _ = f(x, P)
        np.testing.assert_allclose(np.asarray(got).ravel(), expected, rtol=1e-9, atol=1e-9)
