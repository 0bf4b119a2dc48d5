"""Methods B, C, D (Siegloff & Choi §IV-B) against independent hand computations."""

import numpy as np
import pytest

from wheelload.estimators.family.algebraic import Algebraic
from wheelload.estimators.family.quasi_static import QuasiStatic, StaticTransfer
from wheelload.estimators.family.suspension_only import SuspensionOnly
from wheelload.estimators.protocol import SuspensionModel
from wheelload.estimators.result import StepFlag
from wheelload.estimators.samples import step_through
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, ModelParameters, static_loads

N = 400
DT = 0.01


def constant_log(acc, d=(0.0, 0.0, 0.0, 0.0), vx=0.0, n=N) -> Signals:
    return Signals(
        t=DT * np.arange(1, n + 1),
        vx=np.full(n, vx),
        acc=np.tile(np.asarray(acc, float), (n, 1)),
        d=np.tile(np.asarray(d, float), (n, 1)),
        v=np.zeros((n, 4)),
    )


def rigid_body_on_springs(vehicle, acc):
    """Loads of a rigid body on four corner springs and two anti-roll bars in steady acceleration.

    Written out by hand from the vehicle file (no model Function): body heave z (down), pitch
    theta (nose down) and roll phi (right down) give corner compressions
    d_i = z + x_i theta - y_i phi; corner loads F = F0 + k d + ARB; solve force and moment balance
    about the whole-vehicle CG with specific force (ax, ay, az), no aerodynamics (vx = 0).
    """
    p = ModelParameters.from_vehicle(vehicle)
    x = np.array([p.lf, p.lf, -p.lr, -p.lr])
    y = np.array([p.track_front, -p.track_front, p.track_rear, -p.track_rear]) / 2
    k = np.array([p.spring_front] * 2 + [p.spring_rear] * 2)
    K = np.diag(k)
    bars = ((0, p.arb_rate_front, p.arb_ratio_front), (2, p.arb_rate_rear, p.arb_ratio_rear))
    for left, rate, ratio in bars:
        bar = rate * ratio * np.array([[1.0, -1.0], [-1.0, 1.0]])
        K[left : left + 2, left : left + 2] += bar
    G = np.column_stack([np.ones(4), x, -y])  # d = G q, q = (z, theta, phi)
    F0 = static_loads(vehicle)
    ax, ay, az = acc
    m, h = p.mass, p.cg_height
    # Sum of loads = m az; pitch moment about the CG: sum x_i F_i = -m h ax; roll: sum y_i F_i =
    # -m h ay (the ground pushes up at the contacts, h below the CG).
    rows = np.vstack([np.ones(4), x, y])
    target = np.array([m * az, -m * h * ax, -m * h * ay])
    q = np.linalg.solve(rows @ K @ G, target - rows @ F0)
    return F0 + K @ G @ q


@pytest.mark.parametrize("acc", [(0.0, 0.0, GRAVITY), (3.0, -5.0, GRAVITY), (-7.0, 8.0, 10.5)])
def test_quasi_static_is_exact_on_rigid_body_steady_state(vehicle, acc):
    expected = rigid_body_on_springs(vehicle, acc)
    loads = QuasiStatic(vehicle, suspension=SuspensionModel.PAPER).run(constant_log(acc)).loads
    # Same linear algebra, two derivations: agreement to rounding (1e-9 of the load).
    np.testing.assert_allclose(loads, np.tile(expected, (N, 1)), rtol=1e-9)


def test_quasi_static_satisfies_the_equilibrium_with_aero(vehicle):
    estimate = QuasiStatic(vehicle, suspension=SuspensionModel.PAPER).run(
        constant_log((2.0, 4.0, GRAVITY), vx=40.0)
    )
    assert np.max(np.abs(estimate.residual)) < 1e-6  # N, N m: rounding
    assert not estimate.has_std and np.all(estimate.std == 0)


@pytest.mark.parametrize("acc", [(3.0, -5.0, GRAVITY), (-7.0, 8.0, 10.5)])
def test_paper_c_is_static_loads_plus_rigid_transfer(vehicle, acc):
    """C-paper written out from the file's numbers: F0 -/+ m h ax / 2L (front/rear), lateral
    m h ay split by the static axle loads (front lr / L), left wheels lighter for ay > 0;
    no az and no aero (vx = 40 m/s changes nothing)."""
    p = ModelParameters.from_vehicle(vehicle)
    m, h, lf, lr = p.mass, p.cg_height, p.lf, p.lr
    L = lf + lr
    ax, ay, _ = acc
    longitudinal = m * h * ax / (2 * L) * np.array([-1.0, -1.0, 1.0, 1.0])
    lateral = (
        m
        * h
        * ay
        / L
        * np.array([-lr / p.track_front, lr / p.track_front, -lf / p.track_rear, lf / p.track_rear])
    )
    expected = static_loads(vehicle) + longitudinal + lateral
    loads = StaticTransfer(vehicle).run(constant_log(acc, vx=40.0)).loads
    # Same arithmetic, two derivations: agreement to rounding (1e-9 of the load).
    np.testing.assert_allclose(loads, np.tile(expected, (N, 1)), rtol=1e-9)
    # The strengthened C meets the equilibrium with az and lift: it differs here.
    strong = QuasiStatic(vehicle, suspension=SuspensionModel.PAPER).run(constant_log(acc, vx=40.0))
    assert np.max(np.abs(strong.loads[-1] - expected)) > 50.0  # N


def test_suspension_only_equals_the_suspension_model_written_out(vehicle):
    rng = np.random.default_rng(1)
    d = rng.uniform(-0.03, 0.03, (N, 4))
    v = rng.uniform(-0.5, 0.5, (N, 4))
    signals = Signals(
        t=DT * np.arange(1, N + 1), vx=np.full(N, 20.0),
        acc=np.tile([0.0, 0.0, GRAVITY], (N, 1)), d=d, v=v,
    )  # fmt: skip
    s = vehicle.suspension
    expected = static_loads(vehicle) + np.zeros((N, 4))
    for i, axle in enumerate((s.front, s.front, s.rear, s.rear)):
        partner = i ^ 1
        damper = np.where(v[:, i] >= 0, axle.damper_push, axle.damper_pull) * v[:, i]
        bar = axle.arb_rate * axle.arb_ratio * (d[:, i] - d[:, partner])
        expected[:, i] += axle.spring_rate * d[:, i] + damper + bar
    np.testing.assert_allclose(
        SuspensionOnly(vehicle, suspension=SuspensionModel.PAPER).run(signals).loads,
        expected,
        rtol=1e-12,
    )


def test_suspension_only_holds_a_wheel_with_a_missing_travel(vehicle):
    signals = constant_log((0.0, 0.0, GRAVITY), d=[0.01, 0.0, 0.0, 0.0], n=10)
    d = signals.d.copy()
    d[5:, 0] = np.nan
    broken = Signals(t=signals.t, vx=signals.vx, acc=signals.acc, d=d, v=signals.v)
    estimate = SuspensionOnly(vehicle).run(broken)
    assert np.all(np.isfinite(estimate.loads))
    # FL and its anti-roll-bar partner FR depend on d_fl: both held at their last value.
    np.testing.assert_array_equal(estimate.loads[5:, :2], np.tile(estimate.loads[4, :2], (5, 1)))
    assert np.all(estimate.flags[5:] & StepFlag.SUSPENSION_FL_SKIPPED)
    assert np.all(estimate.flags[5:] & StepFlag.SUSPENSION_FR_SKIPPED)
    assert not np.any(estimate.flags[:5])


def test_algebraic_recovers_the_loads_on_a_grade(vehicle):
    # At rest on a 20 % uphill grade with the body level to the road: specific force
    # (g sin a, 0, g cos a). By hand, moments about the contacts along the grade:
    # front axle = m g (l_r cos a - h sin a) / L.
    grade = np.arctan(0.2)
    estimate = Algebraic(vehicle, suspension=SuspensionModel.PAPER).run(
        constant_log((GRAVITY * np.sin(grade), 0, GRAVITY * np.cos(grade)))
    )
    p = ModelParameters.from_vehicle(vehicle)
    L = p.lf + p.lr
    front = p.mass * GRAVITY * (p.lr * np.cos(grade) - p.cg_height * np.sin(grade)) / L / 2
    rear = p.mass * GRAVITY * (p.lf * np.cos(grade) + p.cg_height * np.sin(grade)) / L / 2
    np.testing.assert_allclose(estimate.loads[-1], [front, front, rear, rear], rtol=1e-12)


def test_algebraic_removes_body_pitch_and_roll_from_the_specific_force(vehicle):
    # Level road, at rest, body pitched nose down and rolled right down relative to the road:
    # the accelerometer reads gravity tilted into x and y. Once the low-pass attitude settles
    # (5 s = 31 time constants at 1 Hz) the road-frame specific force is (0, 0, g) again and
    # the loads are the static ones; without the rotation they would move by ~1 %.
    p = ModelParameters.from_vehicle(vehicle)
    pitch, roll = 0.01, 0.02
    d = np.array([
        p.lf * pitch - p.track_front / 2 * roll, p.lf * pitch + p.track_front / 2 * roll,
        -p.lr * pitch - p.track_rear / 2 * roll, -p.lr * pitch + p.track_rear / 2 * roll,
    ])  # fmt: skip
    R_y = np.array(
        [[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0], [-np.sin(pitch), 0, np.cos(pitch)]]
    )
    R_x = np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)], [0, np.sin(roll), np.cos(roll)]])
    body = (R_y @ R_x).T @ np.array([0.0, 0.0, GRAVITY])  # gravity reaction in body axes
    assert body[0] < 0 and body[1] > 0  # nose down reads -x, right down reads +y
    estimate = Algebraic(vehicle, suspension=SuspensionModel.PAPER).run(
        constant_log(body, d=d, n=500)
    )
    static = p.mass * GRAVITY / (2 * (p.lf + p.lr)) * np.array([p.lr, p.lr, p.lf, p.lf])
    np.testing.assert_allclose(estimate.loads[-1], static, rtol=1e-9)
    assert np.max(np.abs(estimate.loads[0] - static)) > 20.0  # the filter starts level


@pytest.mark.parametrize("method", [Algebraic, QuasiStatic, StaticTransfer, SuspensionOnly])
def test_run_equals_repeated_step(vehicle, method):
    rng = np.random.default_rng(2)
    base = constant_log((1.0, -2.0, GRAVITY), vx=20.0, n=60)
    d = base.d + rng.normal(0, 0.005, base.d.shape)
    acc = base.acc + rng.normal(0, 0.5, base.acc.shape)
    acc[30, 1] = np.nan
    signals = Signals(t=base.t, vx=base.vx, acc=acc, d=d, v=base.v)
    estimator = method(vehicle)
    run, steps = estimator.run(signals), step_through(estimator, signals)
    # One CasADi Function, once in generated C and once in Python: rounding only.
    np.testing.assert_allclose(run.loads, steps.loads, rtol=1e-12)
    np.testing.assert_array_equal(run.flags, steps.flags)
    assert np.all(np.isfinite(run.loads)) and np.all(np.isfinite(run.residual))
    assert run.flags[30] & StepFlag.ROLL_SKIPPED
