"""Methods E, E+C and F (Siegloff & Choi §IV-B, §IV-E2) against independent computations."""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from wheelload.estimators.family.quarter_car import QuarterCarObserver
from wheelload.estimators.family.quarter_car_constrained import ConstrainedQuarterCar
from wheelload.estimators.family.strong_tracking_ukf import (
    MEASUREMENT_NOISE,
    PROCESS_NOISE,
    StrongTrackingUKF,
)
from wheelload.estimators.family.suspension_only import SuspensionOnly
from wheelload.estimators.kf.tuning import tuning_vector
from wheelload.estimators.logs.signals import read_log
from wheelload.estimators.protocol import SuspensionModel, sample_intervals
from wheelload.estimators.result import StepFlag
from wheelload.estimators.samples import step_through
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, ModelParameters, paper_equilibrium_function, static_loads
from wheelload.studies.pipeline.example_log import example_log_path


def rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


def quarter_cars_over_a_bump(vehicle, rate=1000.0, duration=1.5):
    """Front and rear quarter cars (left = right) over a 2 cm, 0.2 s bump, written out by hand.

    Sprung corner mass m_s = F0/g - m_u, spring k, asymmetric linear damper, tyre k_t; states
    from static equilibrium. The body IMU signals are built so that the rigid body's corners
    move as the two quarter cars: a_f = az - g - x_f wy_dot, a_r = az - g - x_r wy_dot.
    Returns the log (with reference tyre loads) at ``rate``.
    """
    F0 = static_loads(vehicle)[[0, 2]]
    axles = (vehicle.suspension.front, vehicle.suspension.rear)
    m_u = np.array([vehicle.mass.unsprung_front, vehicle.mass.unsprung_rear]) / 2
    m_s = F0 / GRAVITY - m_u
    k_t = np.array([vehicle.tyres.vertical_stiffness_front, vehicle.tyres.vertical_stiffness_rear])

    def road(t):
        phase = np.clip((t - 0.3) / 0.2, 0.0, 1.0)
        return 0.01 * (1 - np.cos(2 * np.pi * phase))

    def rhs(t, y):
        out = []
        for a in range(2):
            zs, zs_dot, zu, zu_dot = y[4 * a : 4 * a + 4]
            v = zu_dot - zs_dot
            damper = (axles[a].damper_push if v >= 0 else axles[a].damper_pull) * v
            F_s = axles[a].spring_rate * (zu - zs) + damper  # dynamic part
            F_t = k_t[a] * (road(t) - zu)
            out += [zs_dot, F_s / m_s[a], zu_dot, (F_t - F_s) / m_u[a]]
        return out

    t = np.arange(1, int(duration * rate) + 1) / rate
    sol = solve_ivp(rhs, (0, t[-1]), np.zeros(8), t_eval=t, max_step=1e-4, rtol=1e-9, atol=1e-12)
    y = sol.y
    deriv = np.array([rhs(tk, y[:, k]) for k, tk in enumerate(t)]).T
    d = np.column_stack([y[2] - y[0], y[6] - y[4]])
    v = np.column_stack([y[3] - y[1], y[7] - y[5]])
    a_s = np.column_stack([deriv[1], deriv[5]])
    F = F0 + np.column_stack([k_t[0] * (road(t) - y[2]), k_t[1] * (road(t) - y[6])])
    imu = np.asarray(vehicle.geometry.imu_position)
    x_f, x_r = vehicle.geometry.lf - imu[0], -vehicle.geometry.lr - imu[0]
    wy_dot = -(a_s[:, 0] - a_s[:, 1]) / (x_f - x_r)
    az = GRAVITY + a_s[:, 0] + x_f * wy_dot
    # Gyro rate whose backward difference is the sampled angular acceleration.
    wy = np.cumsum(wy_dot) / rate
    pick = [0, 0, 1, 1]
    return Signals(
        t=t,
        vx=np.zeros_like(t),
        acc=np.column_stack([np.zeros_like(t), np.zeros_like(t), az]),
        d=d[:, pick],
        v=v[:, pick],
        rates=np.column_stack([np.zeros_like(t), wy, np.zeros_like(t)]),
        reference=F[:, pick],
    )


@pytest.fixture(scope="module")
def bump(vehicle):
    return quarter_cars_over_a_bump(vehicle)


def test_quarter_car_observer_recovers_the_unsprung_inertia(vehicle, bump):
    # The suspension load (method D) misses m_u z_u'' (wheel hop at ~14 Hz after the bump); the
    # observer recovers it up to its lag, so its error shrinks as its poles get faster.
    error_d = rms(SuspensionOnly(vehicle).run(bump).loads - bump.reference)
    errors = [
        rms(QuarterCarObserver(vehicle, bandwidth=f).run(bump).loads - bump.reference)
        for f in (25.0, 50.0, 150.0)
    ]
    assert error_d > 100.0
    assert errors[0] < 0.6 * error_d  # the default bandwidth
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.1 * error_d


def numpy_two_stage(z, A, b, dt, tuning, x0, P0):
    """The two-stage KF in joint form (equal to the sequential updates), z given."""
    x, P = x0.copy(), P0.copy()
    H = np.vstack([np.eye(4), A])
    out = np.empty_like(z)
    for k in range(len(z)):
        P = P + tuning[0] * dt[k] * np.eye(4)
        R = np.diag(np.concatenate([np.full(4, tuning[1]), tuning[2:5]]) / dt[k])
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        x = x + K @ (np.concatenate([z[k], b[k]]) - H @ x)
        IKH = np.eye(4) - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        out[k] = x
    return out


@pytest.fixture(scope="module")
def example():
    return read_log(example_log_path())


def test_constrained_observer_is_the_two_stage_filter_on_the_observer_output(vehicle, example):
    front = QuarterCarObserver(vehicle, suspension=SuspensionModel.PAPER).run(example).loads
    constrained = ConstrainedQuarterCar(vehicle, suspension=SuspensionModel.PAPER).run(example)
    p = ModelParameters.from_vehicle(vehicle).vector()
    n = len(example)
    A, b = paper_equilibrium_function().map(n)(example.acc.T, example.vx[None], p)
    expected = numpy_two_stage(
        front, np.asarray(A)[:, :4], np.asarray(b).T, sample_intervals(example.t),
        tuning_vector(vehicle), static_loads(vehicle),
        vehicle.filter.initial_std**2 * np.eye(4),
    )  # fmt: skip
    # Sequential vs joint update of one linear-Gaussian problem: rounding (1e-9 relative).
    np.testing.assert_allclose(constrained.loads, expected, rtol=1e-9)
    # The soft equilibrium pulls the observer's loads towards A x = b. Bound 0.6
    # (was 0.5): the example log now comes from the plant with link forces and
    # body inertia, whose own loads leave a residual on the paper's rows (about
    # 64 N vertical, 57 N m roll RMS on the lane change) that no filter on those
    # rows removes; measured ratio 0.41 on the previous example log, 0.50 now.
    # Bound 0.8 (was 0.6): the bundled suspension noise of 200 N^2 s (was 625) trusts the
    # observer's rows more; measured 0.73.
    observer = QuarterCarObserver(vehicle, suspension=SuspensionModel.PAPER).run(example)
    assert rms(constrained.residual) < 0.8 * rms(observer.residual)


def linear_vehicle(vehicle, load_noise=None):
    """Symmetric dampers (the quarter-car model becomes linear); optional load random walk."""
    s = vehicle.suspension
    front = dataclasses.replace(s.front, damper_pull=s.front.damper_push)
    rear = dataclasses.replace(s.rear, damper_pull=s.rear.damper_push)
    changed = vehicle.replace(suspension=dataclasses.replace(s, front=front, rear=rear))
    if load_noise is not None:
        tuning = dataclasses.replace(changed.filter, process_noise_density=load_noise)
        changed = changed.replace(filter=tuning)
    return changed


def linear_kf(vehicle, signals):
    """The per-corner KF of the linear quarter car, RK4-discretised, written out in numpy."""
    n = len(signals)
    dt = sample_intervals(signals.t)
    F0 = static_loads(vehicle)
    axles = [vehicle.suspension.front] * 2 + [vehicle.suspension.rear] * 2
    m_u = np.array([vehicle.mass.unsprung_front] * 2 + [vehicle.mass.unsprung_rear] * 2) / 2
    q = np.array([*PROCESS_NOISE, vehicle.filter.process_noise_density])
    R = np.diag(MEASUREMENT_NOISE)
    H = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    loads, stds = np.empty((n, 4)), np.empty((n, 4))
    for i in range(4):
        ax = axles[i]
        k = ax.spring_rate + ax.arb_rate * ax.arb_ratio
        Ac = np.array([[0, 1, 0], [-k / m_u[i], -ax.damper_push / m_u[i], 1 / m_u[i]], [0, 0, 0]])
        x = np.array([0.0, 0.0, F0[i]])
        P = np.diag([0.05**2, 1.0**2, vehicle.filter.initial_std**2])
        for j in range(n):
            h = dt[j]
            M = h * Ac
            Phi = np.eye(3) + M + M @ M / 2 + M @ M @ M / 6 + M @ M @ M @ M / 24
            Gamma = h * (np.eye(3) + M / 2 + M @ M / 6 + M @ M @ M / 24)
            partner = signals.d[j, i ^ 1]
            a_s = signals.acc[j, 2] - GRAVITY
            drive = np.array([0, (-F0[i] + ax.arb_rate * ax.arb_ratio * partner) / m_u[i] - a_s, 0])
            x = Phi @ x + Gamma @ drive
            P = Phi @ P @ Phi.T + np.diag(q) * h
            y = np.array([signals.d[j, i], signals.v[j, i]])
            S = H @ P @ H.T + R
            K = np.linalg.solve(S, H @ P).T
            x = x + K @ (y - H @ x)
            I_KH = np.eye(3) - K @ H
            P = I_KH @ P @ I_KH.T + K @ R @ K.T
            loads[j, i], stds[j, i] = x[2], np.sqrt(P[2, 2])
    return loads, stds


def test_unscented_filter_equals_the_linear_kf_on_a_linear_model(vehicle):
    # Linear process, fading off: the unscented transform is exact, so the UKF is the KF.
    linear = linear_vehicle(vehicle)
    rng = np.random.default_rng(4)
    n = 300
    t = 0.01 * np.arange(1, n + 1)
    d = 0.01 * np.sin(2 * np.pi * 1.3 * t)[:, None] * [1, 0.5, -0.3, 0.8] + rng.normal(
        0, 1e-4, (n, 4)
    )
    v = np.gradient(d, t, axis=0) + rng.normal(0, 3e-3, (n, 4))
    acc = np.column_stack([np.zeros(n), np.zeros(n), GRAVITY + rng.normal(0, 0.3, n)])
    signals = Signals(t=t, vx=np.zeros(n), acc=acc, d=d, v=v)
    ukf = StrongTrackingUKF(linear, max_fading=1.0, suspension=SuspensionModel.PAPER).run(signals)
    loads, stds = linear_kf(linear, signals)
    # Same algebra in two orders of evaluation: 1e-7 relative (the covariances span 1e-8..1e6).
    np.testing.assert_allclose(ukf.loads, loads, rtol=1e-7)
    np.testing.assert_allclose(ukf.std, stds, rtol=1e-6)


def test_strong_tracking_follows_an_abrupt_load_change_faster(vehicle):
    # A slow load random walk (q = 1e5 N^2/s) makes the plain UKF sluggish after a 2 kN step of
    # the tyre load at t = 1 s; the fading factor inflates P on the large innovations.
    linear = linear_vehicle(vehicle, load_noise=1e5)
    m_u = vehicle.mass.unsprung_front / 2
    k = vehicle.suspension.front.spring_rate  # left = right: the anti-roll bar is idle
    c = vehicle.suspension.front.damper_push

    def rhs(t, y):
        step = 2000.0 if t >= 1.0 else 0.0
        return [y[1], (step - k * y[0] - c * y[1]) / m_u]

    t = 0.01 * np.arange(1, 301)
    sol = solve_ivp(rhs, (0, t[-1]), [0, 0], t_eval=t, max_step=1e-3, rtol=1e-10, atol=1e-12)
    d = np.column_stack([sol.y[0]] * 2 + [np.zeros_like(t)] * 2)
    v = np.column_stack([sol.y[1]] * 2 + [np.zeros_like(t)] * 2)
    acc = np.column_stack([np.zeros_like(t), np.zeros_like(t), np.full_like(t, GRAVITY)])
    signals = Signals(t=t, vx=np.zeros_like(t), acc=acc, d=d, v=v)
    truth = static_loads(vehicle)[0] + 2000.0 * (t >= 1.0)
    after = (t > 1.005) & (t < 1.1)  # from the first sample that sees the motion
    strong = (
        StrongTrackingUKF(linear, suspension=SuspensionModel.PAPER).run(signals).loads[after, 0]
        - truth[after]
    )
    plain = (
        StrongTrackingUKF(linear, max_fading=1.0, suspension=SuspensionModel.PAPER)
        .run(signals)
        .loads[after, 0]
        - truth[after]
    )
    assert rms(strong) < 0.5 * rms(plain)


@pytest.mark.parametrize("method", [QuarterCarObserver, ConstrainedQuarterCar, StrongTrackingUKF])
def test_run_equals_repeated_step_and_missing_samples_hold(vehicle, example, method):
    signals = example.slice(0, 80)
    d = signals.d.copy()
    d[40:45, 2] = np.nan
    rates = signals.rates.copy()
    rates[20:30] = np.nan
    broken = dataclasses.replace(signals, d=d, rates=rates)
    estimator = method(vehicle)
    run, steps = estimator.run(broken), step_through(estimator, broken)
    # One CasADi Function, in generated C and in Python: rounding only.
    np.testing.assert_allclose(run.loads, steps.loads, rtol=1e-10)
    np.testing.assert_allclose(run.std, steps.std, rtol=1e-8, atol=1e-9)
    np.testing.assert_array_equal(run.flags, steps.flags)
    assert np.all(np.isfinite(run.loads)) and np.all(np.isfinite(run.std))
    assert np.all(run.flags[40:45] & StepFlag.SUSPENSION_RL_SKIPPED)
    assert not np.any(run.flags[:40] & StepFlag.SUSPENSION_RL_SKIPPED)
