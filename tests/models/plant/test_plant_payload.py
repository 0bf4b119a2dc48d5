"""A payload on the plant's sprung body, against independent statics and mass properties."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from wheelload.models import GRAVITY, static_loads, vehicle_mass_centre
from wheelload.models.payload import (
    Payload,
    RigidBody,
    inertia_about,
    loaded_mass_properties,
    with_payload,
    with_point_mass,
)
from wheelload.models.plant.dynamics import (
    INPUT_NAMES,
    STATE,
    chunk_function,
    corners,
    plant_functions,
)
from wheelload.models.plant.equilibrium import initial_state
from wheelload.studies.drive.payload_schedule import PayloadChange, PayloadSchedule
from wheelload.studies.drive.roads import build_road
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import scenario_run
from wheelload.studies.drive.simulation import simulate

LOADS = ["fz_fl", "fz_fr", "fz_rl", "fz_rr"]
PAYLOAD = Payload(mass=150.0, x=-0.6, y=0.35, z=0.2)  # behind the CG, left, above it


def _inertia_by_definition(masses, points, centre):
    """I_jk = sum m (delta_jk |r|^2 - r_j r_k), r from ``centre``: the definition, looped."""
    inertia = np.zeros((3, 3))
    for m, p in zip(masses, points, strict=True):
        r = np.asarray(p) - centre
        for j in range(3):
            for k in range(3):
                inertia[j, k] += m * ((j == k) * (r @ r) - r[j] * r[k])
    return inertia


def test_point_masses_combine_as_their_definition_with_numbers_and_symbols():
    # A body made of two point masses, then a payload: the combined centre and inertia
    # equal the sums over the three masses (to 1e-12, rounding).
    a, b = (300.0, np.array([1.0, 0.2, -0.1])), (500.0, np.array([-0.6, -0.1, 0.3]))
    centre = (a[0] * a[1] + b[0] * b[1]) / (a[0] + b[0])
    body = RigidBody(
        mass=a[0] + b[0],
        centre=centre,
        inertia=_inertia_by_definition([a[0], b[0]], [a[1], b[1]], centre),
    )
    loaded = with_payload(body, PAYLOAD)
    masses, points = [a[0], b[0], PAYLOAD.mass], [a[1], b[1], PAYLOAD.position]
    expected_centre = sum(m * p for m, p in zip(masses, points, strict=True)) / sum(masses)
    assert loaded.mass == pytest.approx(950.0, rel=1e-15)
    np.testing.assert_allclose(loaded.centre, expected_centre, rtol=1e-12)
    expected = _inertia_by_definition(masses, points, expected_centre)
    np.testing.assert_allclose(loaded.inertia, expected, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(
        inertia_about(loaded, np.zeros(3)), _inertia_by_definition(masses, points, 0.0), rtol=1e-12
    )
    # The same function on CasADi symbols gives the same numbers.
    m, r = ca.SX.sym("m"), ca.SX.sym("r", 3)
    symbolic = with_point_mass(body, m, r)
    f = ca.Function("f", [m, r], [symbolic.mass, symbolic.centre, symbolic.inertia])
    mass, centre_s, inertia_s = f(PAYLOAD.mass, PAYLOAD.position)
    assert float(mass) == pytest.approx(loaded.mass, rel=1e-15)
    np.testing.assert_allclose(np.asarray(centre_s).ravel(), loaded.centre, rtol=1e-12)
    np.testing.assert_allclose(np.asarray(inertia_s), loaded.inertia, rtol=1e-12, atol=1e-9)


def test_payload_rejects_a_negative_mass_naming_it():
    with pytest.raises(ValueError, match="payload 'mass'"):
        Payload(mass=-1.0)


def _rotation(phi, theta, psi):
    def rx(a):
        return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])

    def ry(a):
        return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])

    def rz(a):
        return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])

    return rz(psi) @ ry(theta) @ rx(phi)


@pytest.fixture(scope="module")
def at_rest(vehicle):
    """State and loads after 2 s at rest on level ground with PAYLOAD, inputs zero."""
    road = build_road(np.arange(-10.0, 50.0, 0.5)).surface
    chunk = chunk_function(vehicle, road, 1000.0, 10, payload=True)
    x = initial_state(vehicle, road, 0.0, 0.0, payload=PAYLOAD)
    u = np.concatenate([np.zeros(len(INPUT_NAMES)), PAYLOAD.values])
    for _ in range(200):
        x, y = chunk(x, u)
    return np.asarray(x).ravel(), np.asarray(y).ravel()[:4]


def test_at_rest_the_payload_adds_its_weight(vehicle, at_rest):
    _, fz = at_rest
    weight = (vehicle.mass.total + PAYLOAD.mass) * GRAVITY
    assert fz.sum() == pytest.approx(weight, rel=1e-3)  # 0.1 %


def test_at_rest_loads_balance_the_moments_of_the_loaded_car(vehicle, at_rest):
    # Statics in the ground frame: the normal loads at the contact points (under the
    # wheel centres on level ground) balance the weights of the sprung body (at the file's
    # sprung CG, the origin), the payload and the unsprung masses (wheel centres), all
    # placed with the body's roll and pitch. Residual moment over the wheelbase (pitch)
    # and over the mean track (roll): 1 N.
    x, fz = at_rest
    rotation = _rotation(x[STATE["phi"]], x[STATE["theta"]], x[STATE["psi"]])
    wheels = corners(vehicle)
    centres = [
        rotation @ np.array([c.x, c.y, c.z_static + x[STATE["d_fl"] + i]])
        for i, c in enumerate(wheels)
    ]
    masses = [vehicle.mass.sprung, PAYLOAD.mass, *(c.unsprung for c in wheels)]
    points = [np.zeros(3), rotation @ PAYLOAD.position, *centres]
    weight_moment = GRAVITY * sum(m * p[:2] for m, p in zip(masses, points, strict=True))
    load_moment = sum(f * p[:2] for f, p in zip(fz, centres, strict=True))
    g = vehicle.geometry
    residual = (load_moment - weight_moment) / np.array(
        [g.lf + g.lr, 0.5 * (g.track_front + g.track_rear)]
    )
    assert np.abs(residual).max() < 1.0
    # With the file's level positions (no tilt) the front axle load is the loaded CG's
    # share to 5 N (measured 1.4 N: the body's pitch moves the high masses back).
    loaded = loaded_mass_properties(vehicle, PAYLOAD)
    lf = vehicle_mass_centre(vehicle).lf - loaded[1]  # cg_x: forward of the file's CG
    front = loaded[0] * GRAVITY * (g.lf + g.lr - lf) / (g.lf + g.lr)
    assert fz[0] + fz[1] == pytest.approx(front, abs=5.0)


def test_at_rest_travel_is_the_extra_load_over_the_wheel_rates(vehicle, at_rest):
    # Per axle the spring and the bar (eq. 6-8) as installed: K d = extra load, with
    # K = [[k + k_b, -k_b], [-k_b, k + k_b]], k_b = arb_rate * arb_ratio; 2 %.
    x, fz = at_rest
    extra = fz - static_loads(vehicle)
    travel = x[STATE["d_fl"] : STATE["d_rr"] + 1]
    for axle, setting in enumerate((vehicle.suspension.front, vehicle.suspension.rear)):
        k, k_b = setting.spring_rate, setting.arb_rate * setting.arb_ratio
        stiffness = np.array([[k + k_b, -k_b], [-k_b, k + k_b]])
        expected = np.linalg.solve(stiffness, extra[2 * axle : 2 * axle + 2])
        np.testing.assert_allclose(travel[2 * axle : 2 * axle + 2], expected, rtol=0.02)
    assert travel.min() > 1e-3  # every corner visibly compressed (> 1 mm)


def test_without_payload_mass_the_payload_plant_is_the_file_plant(vehicle):
    # The loaded-body equations with m_p = 0 reduce to the plant's own: state rates and
    # outputs agree to rounding (1e-9 relative) in a steady turn with rates and slips.
    run = scenario_run("brake-in-turn", vehicle, Options())
    road = run.road.surface
    plain, _ = plant_functions(vehicle, road)
    loaded, _ = plant_functions(vehicle, road, "loaded", payload=True)
    x = initial_state(vehicle, road, 100.0, 20.0, 0.0)
    x[STATE["p"]], x[STATE["q"]], x[STATE["r"]] = 0.05, -0.03, 0.2
    u = np.zeros(len(INPUT_NAMES))
    u[0], u[1:5] = 0.03, 80.0
    xdot, y = (np.asarray(v).ravel() for v in plain(x, u))
    xdot_p, y_p = (np.asarray(v).ravel() for v in loaded(x, np.concatenate([u, [0, 1, 2, 3]])))
    np.testing.assert_allclose(xdot_p, xdot, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(y_p, y, rtol=1e-9, atol=1e-9)


def test_a_change_to_the_same_payload_is_the_constant_payload(vehicle):
    run = scenario_run("standstill", vehicle, Options())
    constant = PayloadSchedule(initial=PAYLOAD)
    same = PayloadSchedule(initial=PAYLOAD, change=PayloadChange(time=1.0, payload=PAYLOAD))
    a = simulate(vehicle, run, payload=constant).frame
    b = simulate(vehicle, run, payload=same).frame
    np.testing.assert_allclose(b[LOADS].to_numpy(), a[LOADS].to_numpy(), rtol=1e-9)


def test_a_passenger_getting_in_at_a_stop_adds_the_weight_then(vehicle):
    run = scenario_run("stop-and-go", vehicle, Options())
    passenger = Payload(mass=80.0, x=-0.1, y=-0.37, z=0.1)
    schedule = PayloadSchedule(change=PayloadChange(time=5.0, payload=passenger))
    frame = simulate(vehicle, run, payload=schedule).frame
    total = frame[LOADS].sum(axis=1).to_numpy()
    t = frame["t"].to_numpy()
    before, after = total[(t > 3.0) & (t < 4.9)], total[(t > 8.0) & (t < 9.9)]
    weight = vehicle.mass.total * GRAVITY
    np.testing.assert_allclose(before, weight, rtol=1e-3)
    np.testing.assert_allclose(after, weight + 80.0 * GRAVITY, rtol=1e-3)
    assert frame["vx"][t < 10.0].abs().max() < 0.1  # standing still while it happens
    assert frame["vx"].iloc[-1] == pytest.approx(80.0 / 3.6, rel=0.02)  # then drives off
    # the passenger sits on the right: the right wheels take the larger share
    extra = frame[LOADS].to_numpy()[(t > 8.0) & (t < 9.9)].mean(axis=0) - static_loads(vehicle)
    assert extra[1] > extra[0] and extra[3] > extra[2]


def test_a_change_while_driving_is_refused_naming_the_time(vehicle):
    run = scenario_run("iso-dlc", vehicle, Options())
    schedule = PayloadSchedule(change=PayloadChange(time=5.0, payload=PAYLOAD))
    with pytest.raises(ValueError, match="payload changes from t = 5 s.*never stands still"):
        simulate(vehicle, run, payload=schedule)


def test_in_a_steady_turn_the_loads_balance_gravity_and_inertia_of_every_mass(vehicle):
    # brake-in-turn before braking: steady 20 m/s on a 100 m radius (0.41 g) with
    # PAYLOAD. Roll moment about the ground line under the body, in the road frame (body
    # roll, pitch and travel from the state): sum F_z,i Y_i = sum_k m_k (g Y_k - a_y Z_k)
    # over the sprung body, the payload and the unsprung masses, with a_y the body's
    # lateral acceleration in that frame and Z_k heights above the road; the tyres' side
    # forces act at the road. Mean residual over the mean track: 3 N (measured 0.6 N; the
    # plant without payload 0.3 N: centripetal terms of the yaw rate left out).
    run = dataclasses.replace(scenario_run("brake-in-turn", vehicle, Options()), stop=190.0)
    frame = simulate(vehicle, run, payload=PayloadSchedule(initial=PAYLOAD)).frame
    steady = frame[(frame["s"] > 120.0) & (frame["s"] < 190.0)]
    wheels = corners(vehicle)
    residuals = []
    for _, row in steady.iterrows():
        rotation = _rotation(row["phi"], row["theta"], row["psi"])
        acc = rotation @ row[["ax_cg", "ay_cg", "az_cg"]].to_numpy(float)
        centres = [
            rotation @ np.array([c.x, c.y, c.z_static + row[f"d_{w}"]])
            for c, w in zip(wheels, ("fl", "fr", "rl", "rr"), strict=True)
        ]
        masses = [vehicle.mass.sprung, PAYLOAD.mass, *(c.unsprung for c in wheels)]
        points = [np.zeros(3), rotation @ PAYLOAD.position, *centres]
        loads = row[LOADS].to_numpy(float) @ np.array([p[1] for p in centres])
        weights = sum(
            m * (GRAVITY * p[1] - acc[1] * (row["z"] + p[2]))
            for m, p in zip(masses, points, strict=True)
        )
        residuals.append(loads - weights)
    g = vehicle.geometry
    assert steady["ay_cg"].mean() == pytest.approx(20.0**2 / 100.0, rel=0.03)
    assert abs(np.mean(residuals)) / (0.5 * (g.track_front + g.track_rear)) < 3.0
