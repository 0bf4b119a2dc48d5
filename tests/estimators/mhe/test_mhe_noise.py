"""The MHE (Python and C), method E+C and the numpy filter weigh their rows with the KF's noise.

With the vehicle file's input-dependent densities (``[filter]``, default 0) every
estimator takes its per-sample :math:`R_s, R_c` from
:func:`~wheelload.models.measurement_noise.measurement_noise_function`. Checks and
tolerances:

- the MHE window's weights against the inverse of the Function's R at each
  sample (same arithmetic, another order): 1e-12 relative;
- the MHE with N = 1, soft constraint, no bounds and the Kalman arrival against
  the two-stage KF with the same densities (the QP's minimiser is the KF update;
  OSQP at 1e-12): 1e-6 N;
- E+C against a numpy joint (stacked) Kalman update of method E's outputs with
  the Function's R (the stacked update equals the sequential one to rounding):
  1e-9 relative; the numpy joint filter against the KF: 1e-9 relative (as
  ``test_kf``);
- the generated C MHE against the Python MHE: 0.1 N (as ``test_mhe_codegen``).

Bit-for-bit identity with the bundled files (densities 0) is what the existing
tests of each estimator pin.
"""

import dataclasses

import numpy as np
import pytest
from c_parity import assert_c_equals_python, mhe_library, needs_gcc

from wheelload.estimators.family.quarter_car import QuarterCarObserver
from wheelload.estimators.family.quarter_car_constrained import ConstrainedQuarterCar
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import Arrival, Constraint, MheSettings, SolverSettings
from wheelload.estimators.mhe.terms import LOAD_SCALE, residual_function
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import ModelParameters
from wheelload.studies.bench.numpy_kf import joint_filter, measurement_noises, pseudo_measurements
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

EXACT = SolverSettings(eps_abs=1e-12, eps_rel=1e-12, polish=True, max_iter=50000)


def noisy_vehicle(vehicle):
    """The vehicle with every input-dependent density non-zero."""
    return vehicle.replace(
        filter=dataclasses.replace(
            vehicle.filter,
            suspension_noise_rate_density=2.0e4,
            suspension_noise_hub_density=3.0,
            constraint_noise_acceleration_density=(2.0e6, 900.0, 600.0),
        )
    )


@pytest.fixture(scope="module")
def noisy(fixed_vehicle):
    return noisy_vehicle(fixed_vehicle)


@pytest.fixture(scope="module")
def drive(fixed_vehicle):
    """A slalom with hub accelerometers (body az plus a corner-wise oscillation)."""
    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    log = synthetic_log(
        fixed_vehicle, slalom(duration=2.0), noise=noise, spring_error=0.08, seed=11
    )
    wave = 3.0 * np.sin(2 * np.pi * 4.0 * log.t[:, None] + np.arange(4))
    return dataclasses.replace(log, hub=log.acc[:, 2:3] + wave)


def noise_spread(R: np.ndarray) -> float:
    """Largest over smallest R of each row along the log (1: constant noise)."""
    return float(np.min(R.max(axis=0) / R.min(axis=0)))


def test_window_weights_are_the_inverse_of_the_noise_functions_R(noisy, drive):
    mhe = MovingHorizonEstimator(noisy, MheSettings(horizon=1))
    n, dt = len(drive), sample_intervals(drive.t)
    R = measurement_noises(drive, mhe.tuning, dt)  # R at each sample's own interval
    assert noise_spread(R) > 1.2  # the densities act on every row
    u = input_matrix(drive)
    valid = np.isfinite(u).astype(float)
    H, g = (np.asarray(o) for o in mhe.terms.map(n)(
        u, valid, dt[None], np.zeros((4, n)), mhe.p, mhe.tuning, 1.0)[:2])  # fmt: skip
    z, A, b = pseudo_measurements(drive, mhe.p)
    for k in range(0, n, 7):
        W_s, W_c = 1.0 / R[k, :4], 1.0 / R[k, 4:]
        expected = np.diag(W_s) + A.T @ np.diag(W_c) @ A
        np.testing.assert_allclose(H[:, k].reshape(4, 4) / LOAD_SCALE**2, expected, rtol=1e-12)
        linear = -(W_s * z[k] + A.T @ (W_c * b[k]))
        np.testing.assert_allclose(g[:, k] / LOAD_SCALE, linear, rtol=1e-12)
    ls, lc = (np.asarray(o) for o in residual_function().map(n)(
        u, valid, dt[None], mhe.p, mhe.tuning)[3:])  # fmt: skip
    np.testing.assert_allclose(np.vstack([ls, lc]).T, np.sqrt(1.0 / R), rtol=1e-12)


def test_one_sample_soft_window_is_the_kf_with_input_dependent_noise(fixed_vehicle, noisy, drive):
    settings = MheSettings(horizon=1, constraint=Constraint.SOFT, bounded=False, solver=EXACT)
    mhe = MovingHorizonEstimator(noisy, settings).run(drive)
    kf = TwoStageKF(noisy).run(drive)
    assert not mhe.fallback.any()
    np.testing.assert_allclose(mhe.loads, kf.loads, rtol=0, atol=1e-6)
    # ... and the check tells the densities apart: the constant-R filter is far from both.
    constant = TwoStageKF(fixed_vehicle).run(drive)
    assert np.max(np.abs(constant.loads - kf.loads)) > 1.0


def test_constrained_quarter_car_updates_with_the_noise_functions_R(noisy, drive):
    """E+C = the stacked Kalman update of method E's outputs and the equilibrium, R per sample."""
    observed = QuarterCarObserver(noisy).run(drive).loads
    loads = ConstrainedQuarterCar(noisy).run(drive).loads
    p = ModelParameters.from_vehicle(noisy).vector()
    kf = TwoStageKF(noisy)
    dt = sample_intervals(drive.t)
    R_all = measurement_noises(drive, kf.tuning, dt)
    assert noise_spread(R_all) > 1.2
    _, A, b = pseudo_measurements(drive, p)
    H = np.vstack([np.eye(4), A])
    x, P = kf.initial_state().x.copy(), kf.initial_state().P.copy()
    q = noisy.filter.process_noise_density
    expected = np.empty_like(loads)
    for k in range(len(drive)):
        P = P + q * dt[k] * np.eye(4)
        R = np.diag(R_all[k])
        K = np.linalg.solve(H @ P @ H.T + R, H @ P).T
        x = x + K @ (np.concatenate([observed[k], b[k]]) - H @ x)
        P = (np.eye(4) - K @ H) @ P
        P = 0.5 * (P + P.T)
        expected[k] = x
    np.testing.assert_allclose(loads, expected, rtol=1e-9)


def test_numpy_joint_filter_is_the_kf_with_input_dependent_noise(noisy, drive):
    kf = TwoStageKF(noisy)
    state = kf.initial_state()
    joint = joint_filter(drive, kf.p, kf.tuning, state.x)
    np.testing.assert_allclose(joint, kf.run(drive).loads, rtol=1e-9)


@needs_gcc
def test_generated_c_mhe_weighs_with_the_noise_function(noisy, drive, tmp_path):
    settings = MheSettings(horizon=5, bounded=True, arrival=Arrival.STEADY_STATE)
    c = mhe_library(noisy, settings, tmp_path, dt=0.01).run(drive)
    python = MovingHorizonEstimator(noisy, settings).run(drive)
    assert np.all(c.status == 1)
    assert_c_equals_python(c.loads, python.loads, rtol=0, atol=0.1)
