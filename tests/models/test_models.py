"""Signs of the equilibrium model (eq. 15-16), each pinned against a hand derivation.

Tolerances are 1e-9 relative: both sides are exact algebra in double precision.
"""

import numpy as np
import pytest

from wheelload.models import (
    GATES,
    GRAVITY,
    equilibrium_function,
    static_loads,
    vehicle_mass_centre,
)
from wheelload.models.inputs import input_vector

PAPER = np.zeros(len(GATES))  # every term beyond the paper gated off


def equilibrium(p, acc, vx=0.0):
    u = np.nan_to_num(input_vector(d=np.zeros(4), acc=acc, vx=vx))
    A, b = equilibrium_function()(u, PAPER, p.vector())
    return np.asarray(A), np.asarray(b).ravel()


def test_static_loads_satisfy_equilibrium_at_rest(vehicle, p):
    A, b = equilibrium(p, [0.0, 0.0, GRAVITY])
    np.testing.assert_allclose(A @ static_loads(vehicle), b, rtol=1e-9, atol=1e-9)


def test_forward_acceleration_loads_the_rear_axle(vehicle, p):
    ax = 3.0
    c = vehicle_mass_centre(vehicle)
    transfer = vehicle.mass.total * c.height * ax / (c.lf + c.lr)  # rigid-body, per axle
    loads = static_loads(vehicle) + 0.5 * transfer * np.array([-1, -1, 1, 1])
    A, b = equilibrium(p, [ax, 0.0, GRAVITY])
    np.testing.assert_allclose(A @ loads, b, rtol=1e-9, atol=1e-6)
    assert b[1] < 0  # front-minus-rear moment falls: the rear gains load


def test_left_turn_loads_the_right_wheels(vehicle, p):
    ay, share = 6.0, 0.55  # any front share of the roll moment
    moment = vehicle.mass.total * vehicle_mass_centre(vehicle).height * ay
    front = share * moment / vehicle.geometry.track_front
    rear = (1 - share) * moment / vehicle.geometry.track_rear
    loads = static_loads(vehicle) + np.array([-front, front, -rear, rear])
    A, b = equilibrium(p, [0.0, ay, GRAVITY])
    np.testing.assert_allclose(A @ loads, b, rtol=1e-9, atol=1e-6)


def test_parked_on_a_grade_loads_the_downhill_axle(vehicle, p):
    theta = np.arctan(0.2)  # nose up on a 20 % grade; specific force ax = +g sin(theta)
    c = vehicle_mass_centre(vehicle)
    m, L = vehicle.mass.total, c.lf + c.lr
    front_axle = m * GRAVITY * (c.lr * np.cos(theta) - c.height * np.sin(theta)) / L
    rear_axle = m * GRAVITY * (c.lf * np.cos(theta) + c.height * np.sin(theta)) / L
    loads = 0.5 * np.array([front_axle, front_axle, rear_axle, rear_axle])
    A, b = equilibrium(p, [GRAVITY * np.sin(theta), 0.0, GRAVITY * np.cos(theta)])
    np.testing.assert_allclose(A @ loads, b, rtol=1e-9, atol=1e-6)


def test_lift_reduces_the_total_and_drag_and_lift_shift_pitch(vehicle, p):
    vx = 50.0
    q = 0.5 * vehicle.aero.air_density * vx**2 * vehicle.aero.reference_area
    lift, drag = q * vehicle.aero.lift_coefficient, q * vehicle.aero.drag_coefficient
    _, still = equilibrium(p, [0.0, 0.0, GRAVITY], 0.0)
    _, moving = equilibrium(p, [0.0, 0.0, GRAVITY], vx)
    assert moving[0] - still[0] == pytest.approx(-lift, rel=1e-9)
    # lift at x_a ahead of the CG unloads the front; drag above the ground loads the rear
    expected = -p.aero_x * lift - (p.cg_height + p.aero_z) * drag
    assert moving[1] - still[1] == pytest.approx(expected, rel=1e-9)
    assert p.aero_x > 0 and moving[1] < still[1]
