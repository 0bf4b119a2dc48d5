"""UMVF (ycoo-umvf paper §4): unbiased tyre-load estimate under an unknown step input.

The reference is an independent simulation of the full three-state quarter car
(eq. 2-4, momenta and deflection) discretised exactly with the inputs held;
the filter runs on the reduced two-state model derived from it.
"""

import casadi as ca
import numpy as np
import pytest
import scipy.linalg

from wheelload.estimators.family.umvf import (
    Umvf,
    UmvfTuning,
    discrete_model,
    umvf_update,
    unknown_input,
)
from wheelload.estimators.protocol import Estimator, SuspensionModel
from wheelload.estimators.samples import step_through
from wheelload.estimators.types import Signals
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.models.family.quarter_car import quarter_car_function, reduced_quarter_car_function

DT = 0.01
QP = np.array([640.0, 45.0, 60000.0, 2700.0])  # sprung, unsprung kg, N/m, N s/m (front corner)


def simulate(inputs: np.ndarray) -> np.ndarray:
    """Measurements [a_s, q~, q_dot] of the full quarter car from rest, inputs held per sample."""
    x, e, u = ca.SX.sym("x", 3), ca.SX.sym("e", 2), ca.SX.sym("u")
    xdot, y = quarter_car_function()(x, e, u, QP)
    A, B = (np.asarray(ca.DM(ca.jacobian(xdot, v))) for v in (x, e))
    C, D = (np.asarray(ca.DM(ca.jacobian(y, v))) for v in (x, e))
    M = np.zeros((5, 5))
    M[:3, :3], M[:3, 3:] = A * DT, B * DT
    E = scipy.linalg.expm(M)
    state, out = np.zeros(3), []
    for e_k in inputs:
        out.append(C @ state + D @ e_k)
        state = E[:3, :3] @ state + E[:3, 3:] @ e_k
    return np.array(out)


def estimate_inputs(measurements: np.ndarray, tuning: UmvfTuning) -> np.ndarray:
    """The filter's estimate of e_{k-1} after each measurement k >= 1."""
    reduced = reduced_quarter_car_function()(QP)
    continuous = tuple(
        np.asarray(m, float).ravel() if m.shape[1] == 1 else np.asarray(m, float) for m in reduced
    )
    model = discrete_model(continuous, DT)
    x, P = np.zeros(2), np.diag(np.square(tuning.initial_std))
    previous = measurements[0] - model.C @ x
    estimates = []
    for y in measurements[1:]:
        x, P, L, innovation = umvf_update(x, P, 0.0, 0.0, y, model, tuning.Q(DT), tuning.R)
        estimates.append(unknown_input(model, L, innovation, previous))
        previous = y - model.C @ x
    return np.array(estimates)


def unknown_steps(n: int) -> np.ndarray:
    """A 500 N tyre-load step at 1 s, a 300 N load-transfer step at 2 s, then a sine."""
    e = np.zeros((n, 2))
    e[100:, 0] = 500.0
    e[200:, 1] = 300.0
    e[300:, 0] += 800.0 * np.sin(0.05 * np.arange(n - 300))
    return e


def test_noise_free_estimate_is_exact_under_unknown_steps():
    """Unbiased by construction: with exact measurements the error is zero (to rounding)."""
    e = unknown_steps(400)
    estimates = estimate_inputs(simulate(e), UmvfTuning())
    assert np.max(np.abs(estimates - e[:-1])) < 1e-6  # N


def test_mean_error_is_zero_with_measurement_noise():
    """30 noisy runs: the mean error at every sample is within 5 standard errors of zero."""
    tuning = UmvfTuning()
    e = unknown_steps(320)
    clean = simulate(e)
    sigma = np.array([tuning.acceleration_std, tuning.travel_std, tuning.travel_rate_std])
    rng = np.random.default_rng(13)
    errors = np.array(
        [
            estimate_inputs(clean + sigma * rng.standard_normal(clean.shape), tuning) - e[:-1]
            for _ in range(30)
        ]
    )
    mean, standard_error = errors.mean(axis=0), errors.std(axis=0) / np.sqrt(len(errors))
    assert np.all(np.abs(mean) < 5.0 * standard_error + 1e-9)
    # The tyre-load channel is informative: its spread stays well below the step.
    assert errors[:, :, 0].std() < 300.0


def test_vehicle_wrapper_runs_and_holds_static_loads_at_rest():
    vehicle = load_vehicle(example_vehicle_path())
    umvf = Umvf(vehicle)
    assert isinstance(umvf, Estimator)
    n = 100
    t = DT * np.arange(1, n + 1)
    d = np.zeros((n, 4))
    d[40, 1] = np.nan
    rest = Signals(
        t=t, vx=np.zeros(n), acc=np.tile([0, 0, 9.80665], (n, 1)), d=d, v=np.zeros((n, 4)),
    )  # fmt: skip
    run = umvf.run(rest)
    assert np.all(np.isfinite(run.loads))
    assert np.allclose(run.loads[-1], umvf.static, atol=1e-6)
    assert run.flags[40] & 2 and not run.flags[39]
    assert np.array_equal(step_through(umvf, rest).loads, run.loads)


def test_compiled_step_equals_the_numpy_reference():
    """The estimator's CasADi step (rank-one closed forms) against eq. 19-29 in numpy."""
    import dataclasses

    vehicle = load_vehicle(example_vehicle_path())
    axles = {
        name: dataclasses.replace(axle, damper_pull=axle.damper_push, arb_rate=0.0)
        for name, axle in (("front", vehicle.suspension.front), ("rear", vehicle.suspension.rear))
    }
    vehicle = vehicle.replace(suspension=dataclasses.replace(vehicle.suspension, **axles))
    umvf = Umvf(vehicle, suspension=SuspensionModel.PAPER)
    n = 150
    rng = np.random.default_rng(5)
    t = DT * np.arange(1, n + 1)
    d = 0.003 * np.sin(2 * np.pi * 2.0 * t)[:, None] * np.array([1.0, 0.7, -0.5, 0.2])
    d = d + 2e-4 * rng.standard_normal((n, 4))
    v = np.gradient(d, t, axis=0)
    az = 9.80665 + 0.5 * np.sin(2 * np.pi * 1.3 * t)
    signals = Signals(
        t=t, vx=np.full(n, 10.0), acc=np.column_stack([np.zeros(n), np.zeros(n), az]), d=d, v=v,
    )  # fmt: skip
    compiled = umvf.run(signals).loads
    tuning = UmvfTuning()
    for i in range(4):
        model = discrete_model(umvf._continuous[i], DT)
        x, P = np.zeros(2), np.diag(np.square(tuning.initial_std))
        y_all = np.column_stack([az - 9.80665, d[:, i], v[:, i]])
        previous = np.zeros(3)
        for k in range(n):
            x, P, L, innovation = umvf_update(
                x, P, 0.0, 0.0, y_all[k], model, tuning.Q(DT), tuning.R
            )
            e = unknown_input(model, L, innovation, previous)
            previous = y_all[k] - model.C @ x
            assert compiled[k, i] == pytest.approx(e[0] + umvf.static[i], abs=1e-6)
