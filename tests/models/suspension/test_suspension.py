"""Signs of the suspension model (eq. 6-8: springs, anti-roll bars, dampers, the
pseudo-measurement), each pinned against a hand derivation.

Tolerances are 1e-12 relative: both sides are exact algebra in double precision.
"""

import dataclasses

import casadi as ca
import numpy as np
import pytest

from wheelload.models import GATES, GRAVITY, static_loads, suspension_function
from wheelload.models.inputs import input_vector
from wheelload.models.suspension.elements import piecewise_damper_force
from wheelload.models.suspension.pseudo_measurement import (
    piecewise_damper_names,
    piecewise_damper_suspension_function,
)

PAPER = np.zeros(len(GATES))  # every term beyond the paper gated off


def suspension(p, d, v):
    u = np.nan_to_num(input_vector(d=d, v=v, acc=[0.0, 0.0, GRAVITY], vx=0.0))
    return np.asarray(suspension_function()(u, PAPER, p.vector())).ravel()


def test_anti_roll_bar_adds_load_to_the_more_compressed_wheel(vehicle, p):
    d = 0.01
    change = suspension(p, [d, 0, 0, 0], [0] * 4) - suspension(p, [0] * 4, [0] * 4)
    front = vehicle.suspension.front
    arb = front.arb_rate * front.arb_ratio * d
    np.testing.assert_allclose(change, [front.spring_rate * d + arb, -arb, 0, 0], rtol=1e-12)
    assert change[0] > front.spring_rate * d and change[1] < 0


def test_anti_roll_bar_wheel_rate_is_linear_in_its_motion_ratio(p):
    """Eq. 6-8 by hand: F_L = k_arb gamma (d_L - d_R). A bar of 20 kN/m with gamma 0.6
    (bar deflection per unit of wheel-travel difference) and 10 mm of difference gives
    20000 * 0.6 * 0.010 = 120 N at the left wheel, -120 N at the right; a squared ratio
    (the wheel-rate convention k gamma^2) would give 72 N. The paper's Table I bar
    (15 000 N/m referred to the wheel-travel difference, gamma = 1) on the rear axle: 150 N.
    """
    bar = dataclasses.replace(p, arb_rate_front=20000.0, arb_ratio_front=0.6)
    d = [0.010, 0.0, 0.0, 0.0]
    change = suspension(bar, d, [0] * 4) - suspension(bar, [0] * 4, [0] * 4)
    spring = bar.spring_front * 0.010
    np.testing.assert_allclose(change, [spring + 120.0, -120.0, 0, 0], rtol=1e-12)
    rear = [0.0, 0.0, 0.0, 0.010]
    change = suspension(p, rear, [0] * 4) - suspension(p, [0] * 4, [0] * 4)
    np.testing.assert_allclose(change[2], -150.0, rtol=1e-12)


def test_damper_is_asymmetric_push_in_bump_pull_in_rebound(vehicle, p):
    rear = vehicle.suspension.rear
    zero = suspension(p, [0] * 4, [0] * 4)
    bump = suspension(p, [0] * 4, [0, 0, 0.1, 0]) - zero
    rebound = suspension(p, [0] * 4, [0, 0, -0.1, 0]) - zero
    assert bump[2] == pytest.approx(0.1 * rear.damper_push, rel=1e-12)
    assert rebound[2] == pytest.approx(-0.1 * rear.damper_pull, rel=1e-12)


def test_piecewise_damper_map_by_hand_in_bump_and_rebound():
    """Knots 0.1 and 0.3 m/s; push slopes 2000, 1000, 500 and pull 4000, 2500, 1200 N s/m.
    By hand: at +0.5 m/s 2000*0.1 + 1000*0.2 + 500*0.2 = 500 N; at -0.2 m/s
    -(4000*0.1 + 2500*0.1) = -650 N; at -0.5 m/s -(400 + 500 + 240) = -1140 N."""
    v = ca.SX.sym("v")
    force = ca.Function("f", [v], [piecewise_damper_force(v, (0.1, 0.3), (2000.0, 1000.0, 500.0),
                                                          (4000.0, 2500.0, 1200.0))])  # fmt: skip
    expected = {0.5: 500.0, 0.05: 100.0, 0.0: 0.0, -0.05: -200.0, -0.2: -650.0, -0.5: -1140.0}
    for speed, value in expected.items():
        assert float(force(speed)) == pytest.approx(value, rel=1e-12, abs=1e-12), speed


def test_piecewise_damper_pseudo_measurement_uses_each_axles_own_slopes(p):
    """The suspension function with a two-segment damper map (knot 0.2 m/s), slopes in
    ``piecewise_damper_names`` order (front push, front pull, rear push, rear pull; one
    per segment): each wheel's load at speed minus at rest is its axle's map by hand."""
    knots = (0.2,)
    names = piecewise_damper_names(knots)
    assert names == tuple(f"damper_{side}_{axle}_{j}" for axle in ("front", "rear")
                          for side in ("push", "pull") for j in range(2))  # fmt: skip
    slopes = dict(zip(names, [3000.0, 1500.0, 5000.0, 2000.0, 2800.0, 1400.0, 4500.0, 1800.0]))
    f = piecewise_damper_suspension_function(knots)
    speeds = np.array([0.3, -0.1, -0.4, 0.1])
    u = np.nan_to_num(input_vector(d=np.zeros(4), v=speeds, acc=[0.0, 0.0, GRAVITY], vx=0.0))
    rest = np.nan_to_num(input_vector(d=np.zeros(4), acc=[0.0, 0.0, GRAVITY], vx=0.0))
    values = np.array(list(slopes.values()))
    change = np.asarray(f(u, PAPER, p.vector(), values) - f(rest, PAPER, p.vector(), values))
    # FL +0.3: 3000*0.2 + 1500*0.1; FR -0.1: -5000*0.1; RL -0.4: -(4500*0.2 + 1800*0.2);
    # RR +0.1: 2800*0.1.
    np.testing.assert_allclose(change.ravel(), [750.0, -500.0, -1260.0, 280.0], rtol=1e-12)


def test_pseudo_measurement_at_rest_is_the_static_load(vehicle, p):
    np.testing.assert_allclose(suspension(p, [0] * 4, [0] * 4), static_loads(vehicle), rtol=1e-12)
