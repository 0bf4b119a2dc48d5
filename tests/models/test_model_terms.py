"""Signs and magnitudes of the model terms beyond the paper, each against a hand derivation.

Tolerances: 1e-9 relative where both sides are the same exact algebra; the
road-frame angles are the small-angle travel formulas of
``wheelload.models.terms`` evaluated by hand here.
"""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators import StepFlag
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.types import Sample
from wheelload.models import (
    GATES,
    GRAVITY,
    ModelParameters,
    VehicleFileError,
    equilibrium_function,
    static_loads,
    suspension_function,
    vehicle_from_dict,
    vehicle_mass_centre,
)
from wheelload.models.inputs import input_vector
from wheelload.models.terms import rotation_x, rotation_y, rotation_z
from wheelload.studies.experiments.equilibrium_residuals import paper_model, with_terms


def gates(*on):
    return np.array([1.0 if name in on else 0.0 for name in GATES])


def rows(vehicle, u, *on):
    p = ModelParameters.from_vehicle(vehicle).vector()
    A, b = equilibrium_function()(np.nan_to_num(u), gates(*on), p)
    z = suspension_function()(np.nan_to_num(u), gates(*on), p)
    return np.asarray(A), np.asarray(b).ravel(), np.asarray(z).ravel()


def rotate(matrix, vector):
    return np.asarray(matrix).astype(float) @ np.asarray(vector, dtype=float)


def test_pure_roll_from_travel_is_right_side_down(vehicle):
    """d = (-e, e, -e, e): right wheels compressed, phi > 0 (ISO: right side down)."""
    e = 0.02
    d = np.array([-e, e, -e, e])
    s, t = vehicle.suspension, vehicle.tyres
    g = vehicle.geometry
    corner = []  # travel + tyre deflection (spring + bar load / tyre rate)
    for axle, k_t, track in ((s.front, t.vertical_stiffness_front, g.track_front),
                             (s.rear, t.vertical_stiffness_rear, g.track_rear)):  # fmt: skip
        arb = axle.arb_rate * axle.arb_ratio * 2 * e
        right = e + (axle.spring_rate * e + arb) / k_t
        corner.append(2 * right / track)
    phi = 0.5 * sum(corner)
    a = 5.0  # left turn, m/s^2 in road axes
    f_body = rotate(rotation_x(phi).T, [0.0, a, GRAVITY])  # what the IMU reads in the body
    assert f_body[1] > a and f_body[2] < GRAVITY  # body ay over-reads by g sin(phi)
    u = input_vector(d=d, acc=f_body, vx=0.0)
    _, b, _ = rows(vehicle, u, "road_frame")
    m, m_s = vehicle.mass.total, vehicle.mass.sprung
    c = vehicle_mass_centre(vehicle)
    h_rc = (c.lr * s.front.roll_centre_height + c.lf * s.rear.roll_centre_height) / (c.lf + c.lr)
    shift_y = -m_s / m * (g.cg_height - h_rc) * phi
    np.testing.assert_allclose(b[0], m * GRAVITY, rtol=1e-9)  # the road normal carries m g
    np.testing.assert_allclose(b[2], shift_y * m * GRAVITY - m * c.height * a, rtol=1e-9)
    _, paper_b, _ = rows(vehicle, u)
    assert paper_b[0] < m * GRAVITY - 100.0  # the body-axis row misses m (g - az) > 100 N


def test_pitch_under_braking_moves_the_cg_forward(vehicle):
    e = 0.015
    d = np.array([e, e, -e, -e])  # nose down: theta > 0
    s, t = vehicle.suspension, vehicle.tyres
    front = e + s.front.spring_rate * e / t.vertical_stiffness_front
    rear = -e - s.rear.spring_rate * e / t.vertical_stiffness_rear
    c = vehicle_mass_centre(vehicle)
    theta = (front - rear) / (c.lf + c.lr)
    heave = (c.lr * front + c.lf * rear) / (c.lf + c.lr)
    a = -6.0  # braking, road axes
    f_body = rotate(rotation_y(theta).T, [a, 0.0, GRAVITY])
    _, b, _ = rows(vehicle, input_vector(d=d, acc=f_body, vx=0.0), "road_frame")
    m, m_s = vehicle.mass.total, vehicle.mass.sprung
    h = c.height - m_s / m * heave
    shift_x = m_s / m * vehicle.geometry.cg_height * theta
    assert shift_x > 0
    np.testing.assert_allclose(b[1], shift_x * m * GRAVITY - m * h * a, rtol=1e-9)


def test_body_inertia_signs(vehicle):
    """Nose-down pitch acceleration unloads the front; right-down roll acceleration the left."""
    u = input_vector(d=np.zeros(4), acc=[0, 0, GRAVITY], vx=0.0, rates=[0, 0, 0],
                     rate_dots=[2.0, 1.0, 0.0])  # fmt: skip
    _, off, _ = rows(vehicle, u)
    _, on, _ = rows(vehicle, u, "body_inertia")
    Ixx, Iyy, _ = vehicle.mass.inertia
    np.testing.assert_allclose(on - off, [0.0, -Iyy * 1.0, Ixx * 2.0], rtol=1e-12, atol=1e-9)


def _tyre_force_terms(vehicle, acc):
    """Jacking and tilt per wheel at zero travel, by hand (the docstring of
    models/suspension/pseudo_measurement.py).

    Tyre forces shared by rigid-body loads with the roll split; attitude from the
    tyre deflections under those loads; the specific force ``acc`` in road axes.
    """
    c = vehicle_mass_centre(vehicle)
    L, m, h = c.lf + c.lr, vehicle.mass.total, c.height
    g, t = vehicle.geometry, vehicle.tyres
    split = ModelParameters.from_vehicle(vehicle).roll_split_front
    fx, fy, fz = acc

    def rigid(fx, fy, fz):
        front, rear = m / (2 * L) * (c.lr * fz - h * fx), m / (2 * L) * (c.lf * fz + h * fx)
        lat_f, lat_r = m * h * split / g.track_front * fy, m * h * (1 - split) / g.track_rear * fy
        return np.array([front - lat_f, front + lat_f, rear - lat_r, rear + lat_r])

    loads = rigid(fx, fy, fz)
    rates = np.array([t.vertical_stiffness_front] * 2 + [t.vertical_stiffness_rear] * 2)
    e = (loads - rigid(0.0, 0.0, GRAVITY)) / rates
    phi = 0.5 * ((e[1] - e[0]) / g.track_front + (e[3] - e[2]) / g.track_rear)
    theta = (e[0] + e[1] - e[2] - e[3]) / (2 * L)
    force_x = m * fx  # vx = 0: no drag
    heights = (
        vehicle.suspension.front.roll_centre_height,
        vehicle.suspension.rear.roll_centre_height,
    )
    result = []
    for axle, (arm, track) in enumerate(((c.lr, g.track_front), (c.lf, g.track_rear))):
        force_y = m * fy * arm / L
        left, right = loads[2 * axle], loads[2 * axle + 1]
        jacking = force_y * (right - left) / (left + right) * heights[axle] / track
        for load in (left, right):
            share = load / (left + right)
            tilt = force_y * share * np.sin(phi) - force_x * load / loads.sum() * np.sin(theta)
            result.append(jacking + tilt)
    return np.array(result)


def test_link_loads_follow_roll_centre_and_anti_pitch(vehicle):
    c = vehicle_mass_centre(vehicle)
    L, m = c.lf + c.lr, vehicle.mass.total
    front, rear = vehicle.suspension.front, vehicle.suspension.rear
    g = vehicle.geometry
    a = 4.0
    _, _, z0 = rows(vehicle, input_vector(d=np.zeros(4), acc=[0, a, GRAVITY], vx=0.0))
    _, _, z = rows(vehicle, input_vector(d=np.zeros(4), acc=[0, a, GRAVITY], vx=0.0),
                   "geometric_transfer")  # fmt: skip
    f = m * a * c.lr / L * front.roll_centre_height / g.track_front
    r = m * a * c.lf / L * rear.roll_centre_height / g.track_rear
    tyres = _tyre_force_terms(vehicle, (0.0, a, GRAVITY))
    # a left turn loads the right wheels; jacking and tilt raise every wheel's load
    assert np.all(tyres > 0)
    np.testing.assert_allclose(z - z0, np.array([-f, f, -r, r]) + tyres, rtol=1e-6)
    braking = input_vector(d=np.zeros(4), acc=[-a, 0, GRAVITY], vx=0.0)
    _, _, z = rows(vehicle, braking, "geometric_transfer")
    transfer = m * c.height * a / L  # rigid, per axle, to the front
    shares = [front.anti_pitch_brake] * 2 + [-rear.anti_pitch_brake] * 2
    expected = 0.5 * transfer * np.array(shares) + _tyre_force_terms(vehicle, (-a, 0.0, GRAVITY))
    np.testing.assert_allclose(z - static_loads(vehicle), expected, rtol=1e-6)


def test_stops_and_hub_accelerometers_in_the_pseudo_measurement(vehicle):
    front = vehicle.suspension.front
    x = 0.01
    d = np.array([front.bump_gap + x, 0.0, 0.0, -(vehicle.suspension.rear.rebound_gap + x)])
    hub = np.array([GRAVITY + 20.0, GRAVITY, GRAVITY, GRAVITY])
    u = input_vector(d=d, acc=[0, 0, GRAVITY], vx=0.0, hub=hub)
    _, _, off = rows(vehicle, u)
    _, _, on = rows(vehicle, u, "stops", "unsprung_fl", "unsprung_fr", "unsprung_rl",
                    "unsprung_rr")  # fmt: skip
    rear = vehicle.suspension.rear
    bump = front.stop_rate * x + front.stop_progressive_rate * x**2
    rebound = -(rear.stop_rate * x + rear.stop_progressive_rate * x**2)
    kerb = 0.5 * vehicle.mass.unsprung_front * 20.0
    np.testing.assert_allclose(on - off, [bump + kerb, 0.0, 0.0, rebound], rtol=1e-9, atol=1e-9)


def test_lever_arm_removes_the_centripetal_part_at_the_imu(vehicle):
    """Yaw rate r: an IMU x ahead of the CG reads f_x = f_cg,x - r^2 x."""
    r, x = 0.8, vehicle.geometry.imu_position[0]
    assert x > 0
    at_imu = [-(r**2) * x, 0.0, GRAVITY]
    u = input_vector(d=np.zeros(4), acc=at_imu, vx=0.0, rates=[0, 0, r], rate_dots=[0, 0, 0])
    _, b, _ = rows(vehicle, u, "imu_lever_arm")
    _, level, _ = rows(vehicle, input_vector(d=np.zeros(4), acc=[0, 0, GRAVITY], vx=0.0))
    np.testing.assert_allclose(b, level, rtol=1e-9, atol=1e-6)


def test_mounting_orientation_is_undone(vehicle):
    angles = (0.02, np.radians(5.7), -0.03)  # the Formula Student log's IMU is pitched 5.7 deg
    mounted = vehicle.replace(
        geometry=dataclasses.replace(vehicle.geometry, imu_orientation=angles)
    )
    body = np.array([-3.0, 2.0, GRAVITY])
    R = rotate(rotation_z(angles[2]) @ rotation_y(angles[1]) @ rotation_x(angles[0]), np.eye(3))
    u = input_vector(d=np.zeros(4), acc=R.T @ body, vx=10.0)
    _, b, _ = rows(mounted, u, "imu_mounting")
    _, expected, _ = rows(vehicle, input_vector(d=np.zeros(4), acc=body, vx=10.0))
    np.testing.assert_allclose(b, expected, rtol=1e-9)


def test_missing_optional_inputs_drop_their_terms_and_flag(vehicle):
    kf = TwoStageKF(vehicle)
    state = kf.initial_state()
    sample = Sample(d=np.zeros(4), v=np.zeros(4), acc=np.array([0, 0, GRAVITY]), vx=20.0)
    _, estimate = kf.step(state, sample, 0.01)
    dropped = (StepFlag.BODY_INERTIA_DROPPED | StepFlag.UNSPRUNG_INERTIA_DROPPED
               | StepFlag.IMU_TERMS_DROPPED)  # fmt: skip
    assert estimate.flags[0] == dropped  # every update went ahead
    full = dataclasses.replace(sample, rates=np.zeros(3), rate_dots=np.zeros(3),
                               hub=np.full(4, GRAVITY))  # fmt: skip
    _, estimate = kf.step(state, full, 0.01)
    assert estimate.flags[0] == 0
    no_travel = dataclasses.replace(full, d=np.array([np.nan, 0, 0, 0]))
    _, estimate = kf.step(state, no_travel, 0.01)
    # the anti-roll bar ties FR to d_fl; the equilibrium rows go ahead in body axes
    skipped = StepFlag.SUSPENSION_FL_SKIPPED | StepFlag.SUSPENSION_FR_SKIPPED
    assert estimate.flags[0] == skipped | StepFlag.ROAD_FRAME_OR_LINKS_DROPPED
    quiet = TwoStageKF(paper_model(vehicle))  # terms off: nothing to drop, nothing flagged
    assert quiet.step(quiet.initial_state(), sample, 0.01)[1].flags[0] == 0
    only = TwoStageKF(with_terms(paper_model(vehicle), unsprung_inertia=True))
    assert only.step(only.initial_state(), sample, 0.01)[1].flags[0] == (
        StepFlag.UNSPRUNG_INERTIA_DROPPED
    )


def test_old_vehicle_file_without_model_section_is_rejected(vehicle):
    import tomllib

    from wheelload.models import example_vehicle_path

    table = tomllib.loads(example_vehicle_path().read_text())
    del table["model"]
    del table["mass"]["inertia"]  # an old file lacks new keys too: the section is named first
    with pytest.raises(VehicleFileError, match=r"missing section \[model\].*--template"):
        vehicle_from_dict(table)
    table = tomllib.loads(example_vehicle_path().read_text())
    del table["suspension"]["front"]["roll_centre_height"]
    with pytest.raises(VehicleFileError, match="suspension.front.roll_centre_height.*template"):
        vehicle_from_dict(table)
    table = tomllib.loads(example_vehicle_path().read_text())
    table["model"]["stops"] = 1
    with pytest.raises(VehicleFileError, match="model.stops' must be true or false"):
        vehicle_from_dict(table)
