"""Tyre-force estimators (corner-based paper §III-A/B): defining properties and the plant.

The plant test simulates one iso-dlc run (about 4 s, the compiled chunk cached) and runs
the two-stage KF under both methods: about 15 s in all.
"""

import dataclasses
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelload.estimators.family.tyres.forces import (
    Inputs,
    TyreForces,
    TyreInputError,
    TyreSettings,
    discrete_observer,
    lateral_split,
)
from wheelload.estimators.family.tyres.step import CORE, LateralSplit
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build, methods, tyre_methods
from wheelload.estimators.result import StepFlag
from wheelload.estimators.samples import step_through
from wheelload.models import example_vehicle_path, load_vehicle, vehicle_from_dict
from wheelload.models.family.tyre_forces import (
    PAPER_GAINS,
    body_force_rows,
    load_share_split,
    observer_gains,
    observer_poles,
    tyre_split,
)
from wheelload.studies.drive.scenario_runner import run_scenario


def test_spin_observer_recovers_a_constant_force():
    """Eq. 1 on a synthetic wheel (J = 1.6 kg m^2, R = 0.32 m, T = 300 N m, F_x = 600 N):
    the observer starts rolling steadily, F = T / R = 937.5 N, and settles on 600 N; its
    force error is (J / R) times the spin error's rate, which obeys eq. 9 (3 Hz, damping
    0.8), so after 3 s it is below 1e-6 N (e^{-0.8 * 2 pi 3 * 3} = 2e-20 of 1.7e3 N)."""
    inertia, radius, torque, force, dt = 1.6, 0.32, 300.0, 600.0, 0.01
    phi, gamma1, gamma2, c, d, _ = discrete_observer(inertia, radius, 3.0, 0.8, dt)
    omega = 50.0
    z = np.array([omega, 0.0])
    previous = np.array([torque, omega])
    estimates = [c @ z + d @ previous]
    for _ in range(300):
        omega += dt * (torque - radius * force) / inertia  # exact: the spin is a ramp
        u = np.array([torque, omega])
        z = phi @ z + gamma1 @ previous + gamma2 @ (u - previous)
        estimates.append(c @ z + d @ u)
        previous = u
    assert estimates[0] == pytest.approx(torque / radius)
    assert abs(estimates[-1] - force) < 1e-6


def test_torque_feeds_through_as_in_eq_4():
    """Eq. 4's feed-through: a torque step with the spin unchanged moves the force estimate
    by the step over R at once (the PI observer without it moved only as its poles let)."""
    inertia, radius, dt = 1.6, 0.32, 0.01
    phi, gamma1, gamma2, c, d, _ = discrete_observer(inertia, radius, 1.0, 0.8, dt)
    z, previous = np.array([50.0, 0.0]), np.array([100.0, 50.0])
    u = np.array([-400.0, 50.0])
    z = phi @ z + gamma1 @ previous + gamma2 @ (u - previous)
    assert c @ z + d @ u == pytest.approx(-400.0 / radius, rel=1e-12)


def test_papers_gains_map_by_their_poles():
    """§IV's k1 = 3.41, k2 = 16.22 on the paper's wheel (I_w = 1.7 kg m^2, R_e = 0.346 m):
    eq. 9's poles by hand, omega_n = sqrt(k2 / I_w) = 3.089 rad/s (0.4916 Hz) and
    zeta = R_e k1 / I_w / (2 omega_n) = 0.1123; observer_gains gives the gains back."""
    k = PAPER_GAINS
    frequency, damping = observer_poles(k1=k["k1"], k2=k["k2"], inertia=k["inertia"],
                                        radius=k["radius"])  # fmt: skip
    omega_n = np.sqrt(16.22 / 1.7)
    assert frequency == pytest.approx(omega_n / (2 * np.pi), rel=1e-12)
    assert damping == pytest.approx(0.346 * 3.41 / 1.7 / (2 * omega_n), rel=1e-12)
    assert (frequency, damping) == pytest.approx((0.4916, 0.1123), abs=1e-4)
    gains = observer_gains(inertia=1.7, radius=0.346, frequency=frequency, damping=damping)
    np.testing.assert_allclose(gains, (3.41, 16.22), rtol=1e-12)


def test_spin_observer_poles_are_eq_9():
    """The discrete observer's eigenvalues are exp(s dt) of eq. 9's characteristic
    polynomial J s^2 + R k1 s + k2 (natural frequency and damping as set)."""
    dt, frequency, damping = 0.01, 3.0, 0.8
    phi, *_ = discrete_observer(1.6, 0.32, frequency, damping, dt)
    wn = 2 * np.pi * frequency
    poles = np.roots([1.0, 2 * damping * wn, wn**2])
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(phi)), np.sort_complex(np.exp(poles * dt)), rtol=1e-9
    )


def test_tyre_split_ends():
    """Left/right shares: the cornering stiffnesses' ratio with no axle force, the peak
    forces' ratio at the axle's friction limit, and shares that add to 1 per axle."""
    loads = np.array([2500.0, 5500.0, 3000.0, 6000.0])
    nominal, p_ky2, mu, p_d2 = (3800.0, 4700.0), 2.0, 1.15, -0.1

    def split(axles):
        shares = tyre_split(loads, axles, nominal_loads=nominal, friction=mu,
                            load_sensitivity=p_d2, cornering_load=p_ky2)  # fmt: skip
        return np.array(shares).ravel()

    ky = np.sin(2 * np.arctan(loads / (p_ky2 * np.repeat(nominal, 2))))
    peak = mu * (1 + p_d2 * (loads - np.repeat(nominal, 2)) / np.repeat(nominal, 2)) * loads
    linear, limit = split([0.0, 0.0]), split([1e6, -1e6])
    np.testing.assert_allclose(linear[:2], ky[:2] / ky[:2].sum(), rtol=1e-12)
    np.testing.assert_allclose(limit[2:], peak[2:] / peak[2:].sum(), rtol=1e-12)
    np.testing.assert_allclose(split([3000.0, 2000.0]).reshape(2, 2).sum(axis=1), 1.0)
    # The more loaded tyre takes more, but less than its load share in the linear range.
    assert 0.5 < linear[1] < loads[1] / loads[:2].sum()


def rigid_body_sums(steer, fx, fy, *, lf, lr, track_front, track_rear):
    """Independent check of eq. 2-3: each tyre's (F_x, F_y) turned from its own frame into
    the body's (front wheels by the steer angle), summed, and the yaw moment about the CG
    as x F_y - y F_x over the contact points (x = l_f, -l_r; y = +t/2 left, -t/2 right)."""
    x = np.array([lf, lf, -lr, -lr])
    y = 0.5 * np.array([track_front, -track_front, track_rear, -track_rear])
    angle = np.array([steer, steer, 0.0, 0.0])
    bx = fx * np.cos(angle) - fy * np.sin(angle)
    by = fx * np.sin(angle) + fy * np.cos(angle)
    return np.array([bx.sum(), by.sum(), (x * by - y * bx).sum()])


@settings(max_examples=40, deadline=None)
@given(
    steer=st.floats(-0.3, 0.3),
    fx=st.lists(st.floats(-6000, 6000), min_size=4, max_size=4),
    fy=st.lists(st.floats(-6000, 6000), min_size=4, max_size=4),
    share=st.floats(-0.5, 0.5),
)
def test_body_force_rows_equal_the_rigid_body_sums(steer, fx, fy, share):
    """:func:`body_force_rows` in the state (F_yf, F_yr, e) with e = (F_y,fr - F_y,fl) -
    s F_yf, and the longitudinal forces' offset, equal the rigid-body sums of four tyres
    (yaw row times I_z). Tolerance 1e-9 relative to the largest force: a few products."""
    k = dict(lf=1.2, lr=1.5, track_front=1.6, track_rear=1.58)
    fx, fy = np.array(fx), np.array(fy)
    state = np.array([fy[0] + fy[1], fy[2] + fy[3], (fy[1] - fy[0]) - share * (fy[0] + fy[1])])
    h, offset = body_force_rows(steer, fx, share_front=share, inertia_z=2500.0, **k)
    rows = np.array(h) @ state + np.array(offset).ravel()
    rows[2] *= 2500.0
    scale = 1e-9 * max(1.0, np.abs(fx).max(), np.abs(fy).max())
    np.testing.assert_allclose(rows, rigid_body_sums(steer, fx, fy, **k), rtol=0, atol=scale * 3)


def test_steady_turn_with_steer_and_front_braking():
    """A left turn (F_y 3 kN front, 2.5 kN rear) with 0.05 rad of steer and 1 kN of braking
    on each front wheel, by hand: the braking forces turn with the wheels, so they push
    the car to the right by 2 kN sin(0.05) = 100 N and the front lateral force retards it
    by 3 kN sin(0.05); the front braking's yaw moment is l_f F_xf sin(delta)."""
    steer, k = 0.05, dict(lf=1.2, lr=1.5, track_front=1.6, track_rear=1.58)
    fx = np.array([-1000.0, -1000.0, 0.0, 0.0])
    fy = np.array([1500.0, 1500.0, 1250.0, 1250.0])
    h, offset = body_force_rows(steer, fx, share_front=0.0, inertia_z=1.0, **k)
    rows = np.array(h) @ np.array([3000.0, 2500.0, 0.0]) + np.array(offset).ravel()
    c, s = np.cos(steer), np.sin(steer)
    assert rows[0] == pytest.approx(-2000.0 * c - 3000.0 * s, rel=1e-12)
    assert rows[1] == pytest.approx(3000.0 * c + 2500.0 - 2000.0 * s, rel=1e-12)
    assert rows[2] == pytest.approx(1.2 * (3000.0 * c - 2000.0 * s) - 1.5 * 2500.0, rel=1e-12)
    np.testing.assert_allclose(rows, rigid_body_sums(steer, fx, fy, **k), rtol=1e-12)


def _inputs(vehicle, fyf, fyr, steer, rate, spin):
    """A steady sample whose force sums and gyro agree with the axle forces (yaw balanced
    by the rear force), equal loads (the left/right shares are 1/2) and F_x = 0: the
    torques just overcome the rolling resistance."""
    k = TyreForces(vehicle).constants
    torque = k.radius * k.rolling * 4000.0 * np.tanh(spin / 0.5)
    return Inputs(spin=np.full(4, spin), torque=torque, steer=steer, rate=rate,
                  speed=spin * k.radius[0],
                  sums=np.array([-fyf * np.sin(steer), fyf * np.cos(steer) + fyr]),
                  loads=np.full(4, 4000.0), mass_properties=_file_mass(vehicle))  # fmt: skip


def _file_mass(vehicle):
    return TyreForces(vehicle).file_mass_properties()


def test_force_sums_of_a_steady_sample():
    """S_x, S_y from the accelerometer: m a (level body, no speed: no drag), the
    centripetal r^2 x_imu of the IMU's lever arm removed from a_x."""
    vehicle = load_vehicle(example_vehicle_path())
    method = TyreForces(vehicle)
    m, x_imu, rate = vehicle.mass.total, vehicle.geometry.imu_position[0], 0.4
    acc = np.array([[0.5 - rate**2 * x_imu, 3.0, 9.80665]])
    sums = method.force_sums(np.zeros((1, 4)), acc, [0.0], [rate], method.file_mass_properties())
    np.testing.assert_allclose(sums[0], [0.5 * m, 3.0 * m], rtol=1e-12)
    # The KF's online payload: 150 kg more, the CG 0.2 m further ahead (the IMU's lever arm
    # 0.2 m shorter): the sums are the loaded car's.
    loaded = method.file_mass_properties() + np.array([150.0, 0.2, 0.0, 0.0])
    acc = np.array([[0.5 - rate**2 * (x_imu - 0.2), 3.0, 9.80665]])
    sums = method.force_sums(np.zeros((1, 4)), acc, [0.0], [rate], loaded)
    np.testing.assert_allclose(sums[0], [0.5 * (m + 150), 3.0 * (m + 150)], rtol=1e-12)


def test_lateral_filter_settles_on_the_axle_forces():
    """Eq. 10-16 with the state's yaw rate: a steady turn whose yaw moment balances
    (F_yr from eq. 3 with F_x = 0) is found to 1 N from a zero start in 5 s (random walk,
    exact measurements)."""
    vehicle = load_vehicle(example_vehicle_path())
    method = TyreForces(vehicle)
    k = method.constants
    steer, fyf = 0.03, 3000.0
    h, _ = body_force_rows(steer, np.zeros(4), lf=k.lf, lr=k.lr, track_front=k.track_front,
                           track_rear=k.track_rear, share_front=0.0,
                           inertia_z=k.yaw_inertia)  # fmt: skip
    h = np.array(h)
    fyr = h[2, 0] * fyf / -h[2, 1]  # yaw row = 0
    inputs = _inputs(vehicle, fyf, fyr, steer, 0.4, 60.0)
    core = method.initial_state().core
    for _ in range(500):
        core, _, _, fy, _, _ = method.core_step(core, inputs, 0.01)
    x = core[CORE.x]
    assert x[0] == pytest.approx(fyf, abs=1.0) and x[1] == pytest.approx(fyr, abs=1.0)
    # e (the front difference beyond the split) is seen only through sin(steer) in the
    # yaw row: it is still settling, hence 5 N per wheel.
    assert fy[0] == pytest.approx(fyf / 2, abs=5.0) and fy[3] == pytest.approx(fyr / 2, abs=1.0)


@pytest.fixture(scope="module")
def dlc():
    result = run_scenario("iso-dlc", example_vehicle_path())
    return signals_from_frame(result.log, wiring_checks=False)


def _percent(estimate, reference):
    return 100 * np.sqrt(np.mean((estimate - reference) ** 2) / np.mean(reference**2))


def test_against_the_plant_on_the_lane_change(dlc):
    """Sports car, ISO lane change, measured sensors: pooled RMSE as % of the reference RMS.

    Tolerances: F_x 8 %, F_y 10 % (the issue's goal; measured 4.3 % and 5.7 %); the
    rigid-body split is worse on both (measured 72 % and 16 %). F_z is the KF's own.
    """
    vehicle = load_vehicle(example_vehicle_path())
    forces = build("tyre-forces", vehicle).run(dlc)
    rigid = build("tyre-rigid", vehicle).run(dlc)
    assert _percent(forces.fx, dlc.reference_fx) < 8.0
    assert _percent(forces.fy, dlc.reference_fy) < 10.0
    assert _percent(rigid.fx, dlc.reference_fx) > _percent(forces.fx, dlc.reference_fx)
    assert _percent(rigid.fy, dlc.reference_fy) > _percent(forces.fy, dlc.reference_fy)
    np.testing.assert_array_equal(forces.loads, build("kf", vehicle).run(dlc).loads)
    for values in (forces.fx, forces.fy, forces.fx_std, forces.fy_std):
        assert np.all(np.isfinite(values))
    frame = forces.to_pandas()
    assert {"fx_fl", "fx_std_rr", "fy_rl", "fy_std_fr", "fz_fl", "fz_std_rr"} <= set(frame)


def test_step_equals_run(dlc):
    """The protocol: repeated step gives run's numbers (200 samples of the lane change)."""
    vehicle = load_vehicle(example_vehicle_path())
    short = dlc.slice(500, 700)
    for name in ("tyre-forces", "tyre-rigid"):
        method = build(name, vehicle)
        ran, stepped = method.run(short), step_through(method, short)
        np.testing.assert_allclose(stepped.fy, ran.fy, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(stepped.fx, ran.fx, rtol=1e-9, atol=1e-6)
        np.testing.assert_array_equal(stepped.flags, ran.flags)


def test_high_slip_rides_the_fast_observer(dlc):
    """In high slip (and slip_hold after it) F_x is the fast observer's: with every sample
    after the first flagged (a threshold of 1e-9 /s) and a hold longer than the log, F_x
    (from the first sample, where both start rolling steadily) and its σ (from the first
    flagged one) equal those of a method whose nominal observer runs at the fast one's 30 Hz
    and that never flags (to 1e-9 N: the same algebra); the nominal 1 Hz observer's differ."""
    vehicle = load_vehicle(example_vehicle_path())
    short = dlc.slice(0, 400)
    fast = TyreSettings(slip_ratio_rate=1e-9, slip_hold=1e3)
    flagged = build("tyre-forces", vehicle, settings=fast).run(short)
    assert ((flagged.flags[1:] & StepFlag.HIGH_SLIP) != 0).all()
    quick = TyreSettings(observer_frequency=fast.slip_observer_frequency, slip_ratio_rate=1e9)
    reference = build("tyre-forces", vehicle, settings=quick).run(short)
    assert not (reference.flags & StepFlag.HIGH_SLIP).any()
    np.testing.assert_allclose(flagged.fx, reference.fx, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(flagged.fx_std[1:], reference.fx_std[1:], rtol=0.0, atol=1e-9)
    nominal = build("tyre-forces", vehicle).run(short)
    assert np.max(np.abs(nominal.fx - flagged.fx)) > 1.0


def test_registered_apart_from_the_load_methods(dlc):
    """The tyre methods are built by the registry but not ranked as load estimators; a log
    without wheel spins gets a one-line error naming the channel."""
    assert set(tyre_methods()) == {"tyre-pid", "tyre-lateral", "tyre-forces", "tyre-rigid"}
    assert not set(tyre_methods()) & set(methods())
    vehicle = load_vehicle(example_vehicle_path())
    bare = dataclasses.replace(dlc, spin=None)
    with pytest.raises(TyreInputError, match="no column 'omega_fl'"):
        build("tyre-pid", vehicle).run(bare)
    pid = build("tyre-pid", vehicle).run(dlc.slice(0, 50))
    assert pid.fy is None and pid.fx.shape == (50, 4)


#: The paper's covariances of the lateral filter (§IV, as printed): Q_y = 0.11^2 I and
#: R_y = 0.018^2 I, changing to 0.036^2 I and 0.4^2 I in high slip: the scales on Q and R.
PAPER_HIGH_SLIP = ((0.036 / 0.11) ** 2, (0.4 / 0.018) ** 2)


def lateral_reference(method, x, P, fx_rest, inputs, dt, scales=(1.0, 1.0)):
    """One sample of the lateral filter in numpy (eq. 10-16): random-walk forces, torque
    gain g and S_x bias, the yaw rate integrated by eq. 3's row, then a Kalman update on
    S_x, S_y at the IMU (lever arm m x_imu r_dot) and the gyro's r; F_x = ``fx_rest`` +
    g T / R; the left/right split by F_z shares (the paper's simple alternative,
    TyreSettings(split=LOAD)). Returns x, P, F_y per wheel, F_x."""
    k, s = method.constants, method.settings
    loads = np.asarray(inputs.loads)
    shares = np.concatenate([loads[:2] / loads[:2].sum(), loads[2:] / loads[2:].sum()])

    def rows(fx):
        h, offset = body_force_rows(
            inputs.steer, fx, lf=k.lf, lr=k.lr, track_front=k.track_front,
            track_rear=k.track_rear, share_front=shares[1] - shares[0], inertia_z=k.yaw_inertia,
        )  # fmt: skip
        return np.asarray(h), np.asarray(offset).ravel()

    torque = inputs.torque / k.radius
    (h, offset), (_, by_gain) = rows(fx_rest), rows(torque)
    F = np.eye(6)
    F[3, :3], F[3, 4] = dt * h[2], dt * by_gain[2]
    x = F @ x + np.array([0.0, 0.0, 0.0, dt * offset[2], 0.0, 0.0])
    Q = scales[0] * dt * np.diag([s.force_rate**2, s.force_rate**2, s.split_rate**2,
                                  s.yaw_rate_noise**2, s.torque_gain_rate**2,
                                  s.force_bias_rate**2])  # fmt: skip
    P = F @ P @ F.T + Q
    lever = k.mass * k.imu_x
    H = np.zeros((3, 6))
    H[0, :3], H[0, 4], H[0, 5] = h[0], by_gain[0], 1.0
    H[1, :3], H[1, 4] = h[1] + lever * h[2], by_gain[1] + lever * by_gain[2]
    H[2, 3] = 1.0
    z = np.array([inputs.sums[0] - offset[0], inputs.sums[1] - offset[1] - lever * offset[2],
                  inputs.rate])  # fmt: skip
    R = scales[1] * np.diag([s.force_noise**2, s.force_noise**2, s.gyro_noise**2])
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    x = x + K @ (z - H @ x)
    P = (np.eye(6) - K @ H) @ P @ (np.eye(6) - K @ H).T + K @ R @ K.T
    G = np.array([[shares[0], 0, -0.5], [shares[1], 0, 0.5], [0, shares[2], 0],
                  [0, shares[3], 0]])  # fmt: skip
    return x, P, G @ x[:3], fx_rest + x[4] * torque


@pytest.fixture(scope="module")
def load_split():
    """The F_z split, with random walks of e and r other than 1 (so a square shows)."""
    settings = TyreSettings(split=LateralSplit.LOAD, split_rate=3.0, yaw_rate_noise=0.02)
    return TyreForces(load_vehicle(example_vehicle_path()), settings)


def braking_turn(method, spin=60.0, speed=None, loads=(3200.0, 4600.0, 3600.0, 5100.0)):
    """A braking left turn: unequal torques and loads, steer, yaw rate and force sums."""
    return Inputs(spin=np.full(4, spin), torque=np.array([-420.0, -380.0, -150.0, -170.0]),
                  steer=0.04, rate=0.35,
                  speed=60.0 * method.constants.radius[2] if speed is None else speed,
                  sums=np.array([-3500.0, 9000.0]), loads=np.array(loads),
                  mass_properties=method.file_mass_properties())  # fmt: skip


def test_first_sample_by_hand(load_split):
    """F_x starts rolling steadily: g T / R less the rolling resistance f_r F_z
    tanh(w / 0.5), g the torque gain after the first update; its sigma the spin noise
    through the observer's gain, the rolling resistance's share, the force share and the
    gain's (TyreSettings); F_y is the lateral filter's first update from (0, 0, 0, r, 1, 0)
    with the prior sigmas, against the numpy reference. Tolerance 1e-9 relative: the same
    algebra in another order."""
    method, dt = load_split, 0.01
    inputs = braking_turn(method)
    k, s = method.constants, method.settings
    core, fx, fx_std, fy, fy_std, high_slip = method.core_step(
        method.initial_state().core, inputs, dt
    )
    rolling = k.rolling * inputs.loads * np.tanh(inputs.spin / 0.5)
    x0 = np.array([0.0, 0.0, 0.0, inputs.rate, 1.0, 0.0])
    P0 = np.diag(
        [s.initial_force_std**2] * 2
        + [s.split_std**2, s.gyro_noise**2, s.torque_gain_std**2, s.force_bias_std**2]
    )
    x, P, fy_expected, fx_expected = lateral_reference(method, x0, P0, -rolling, inputs, dt)
    np.testing.assert_allclose(core[CORE.x], x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(core[CORE.P].reshape(6, 6), P, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fy, fy_expected, rtol=1e-9)
    np.testing.assert_allclose(fx, fx_expected, rtol=1e-9)
    gains = np.array([discrete_observer(k.inertia[i], k.radius[i], s.observer_frequency,
                                        s.observer_damping, dt)[5] for i in range(4)])  # fmt: skip
    expected_std = np.sqrt((gains * s.spin_noise) ** 2 + (s.rolling_resistance_std * rolling) ** 2
                           + (s.force_share_std * fx) ** 2
                           + (inputs.torque / k.radius) ** 2 * P[4, 4])  # fmt: skip
    np.testing.assert_allclose(fx_std, expected_std, rtol=1e-9)
    assert np.all(fy_std > 0) and high_slip[0] == 0.0


def slip_by_hand(method, inputs):
    """Each wheel's slip ratio in numpy: (R_e w - v_i) / v_i with R_e = R_0 - F_z / (3 k_t)
    (the KF's loads) and v_i = (v_x - r y_i) cos(steer_i) + r x_i sin(steer_i)."""
    k = method.constants
    radius = k.free_radius - inputs.loads / (3.0 * k.vertical_stiffness)
    x, y = np.array(k.positions).T
    steer = np.array([inputs.steer] * 2 + [0.0] * 2)
    along = (inputs.speed - inputs.rate * y) * np.cos(steer) + inputs.rate * x * np.sin(steer)
    return (radius * inputs.spin - along) / along, radius, along


def test_high_slip_takes_the_papers_covariances(load_split):
    """§IV's switch on the slip condition: a second sample whose slip ratios (by hand,
    :func:`slip_by_hand`) rose by 0.072 in 10 ms (7.2 /s, 1.2 /s after the 50 ms low-pass:
    over the 1 /s threshold): flagged, and with ``switch_covariances`` the lateral update
    equals the reference with the paper's high-slip Q and R (0.036^2 / 0.11^2 and 0.4^2 /
    0.018^2 times the nominal); without it the nominal ones. A rise of 0.048 (0.8 /s after
    the low-pass), the spins and the car's speed rising 5 % together (the wheels rolling
    with the car: the slip unchanged) and no change are nominal."""
    dt = 0.01
    settings = dataclasses.replace(load_split.settings, switch_covariances=True)
    switching = TyreForces(load_split.vehicle, settings)
    first = braking_turn(load_split)
    slip, radius, along = slip_by_hand(load_split, first)

    def spins(rise, speed_scale=1.0):
        return (1.0 + slip + rise) * along * speed_scale / radius

    faster = dataclasses.replace(first, speed=1.05 * first.speed)
    rolling = (1.0 + slip) * slip_by_hand(load_split, faster)[2] / radius
    cases = ((switching, spins(0.072), first.speed, PAPER_HIGH_SLIP, 1.0),
             (load_split, spins(0.072), first.speed, (1.0, 1.0), 1.0),
             (switching, spins(0.048), first.speed, (1.0, 1.0), 0.0),
             (switching, rolling, faster.speed, (1.0, 1.0), 0.0),
             (switching, first.spin, first.speed, (1.0, 1.0), 0.0))  # fmt: skip
    for method, spin, speed, scales, flagged in cases:
        core, *_ = method.core_step(method.initial_state().core, first, dt)
        np.testing.assert_allclose(core[CORE.last_slip], slip, rtol=1e-12, atol=1e-15)
        inputs = dataclasses.replace(first, spin=spin, speed=speed)
        after, fx, _, fy, _, high_slip = method.core_step(core, inputs, dt)
        assert high_slip[0] == flagged
        assert after[CORE.slip_hold] == (settings.slip_hold if flagged else 0.0)
        rest = fx - after[CORE.x][4] * inputs.torque / method.constants.radius
        x, P, fy_expected, _ = lateral_reference(method, core[CORE.x],
                                                 core[CORE.P].reshape(6, 6), rest, inputs,
                                                 dt, scales)  # fmt: skip
        np.testing.assert_allclose(after[CORE.x], x, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(fy, fy_expected, rtol=1e-9)


def test_rigid_body_baseline_splits_by_load_share():
    """load_share_split by hand: 1000 N over loads (1, 1, 2, 4) kN is 125, 125, 250,
    500 N; a negative load (a lifted wheel's estimate) takes no share; no load at all
    takes none either (no division by zero)."""
    loads = np.array([[1000.0, 1000.0, 2000.0, 4000.0], [-500.0, 1000.0, 1000.0, 2000.0],
                      [0.0, 0.0, 0.0, 0.0]])  # fmt: skip
    split = load_share_split(np.array([1000.0, 800.0, 50.0]), loads)
    np.testing.assert_allclose(split, [[125.0, 125.0, 250.0, 500.0], [0.0, 200.0, 200.0, 400.0],
                                       [0.0, 0.0, 0.0, 0.0]], rtol=1e-12)  # fmt: skip


def _vehicle_without(section):
    data = tomllib.loads(example_vehicle_path().read_text(encoding="utf-8"))
    del data[section]
    return vehicle_from_dict(data)


def test_the_vehicle_files_wheels_and_cornering_sections():
    """[wheels] is required (a one-line error naming it and its keys); without
    [cornering] the split is the paper's normal-load share, and asking for the tyre split
    then is a one-line error naming the section."""
    with pytest.raises(TyreInputError, match=r"no \[wheels\] section: .*spin_inertia_front"):
        TyreForces(_vehicle_without("wheels"))
    bare = _vehicle_without("cornering")
    assert lateral_split(bare, None) is LateralSplit.LOAD
    assert lateral_split(load_vehicle(example_vehicle_path()), None) is LateralSplit.TYRE
    with pytest.raises(TyreInputError, match=r"no \[cornering\] section"):
        TyreForces(bare, TyreSettings(split=LateralSplit.TYRE))
