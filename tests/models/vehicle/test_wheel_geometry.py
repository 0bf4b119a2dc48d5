"""Wheel centres and loaded radii: written once, read by the estimators and the plant alike."""

import numpy as np

from wheelload.estimators.family.tyres.forces import vehicle_constants
from wheelload.models.body_attitude import corner_positions
from wheelload.models.mass_properties import static_loads
from wheelload.models.plant.dynamics import corners
from wheelload.models.vehicle.wheel_geometry import loaded_radii, rolling_radius, wheel_centres


def test_wheel_centres_follow_iso_8855(vehicle):
    g = vehicle.geometry
    (fl, fr, rl, rr) = wheel_centres(g)
    assert fl == (g.lf, g.track_front / 2) and fr == (g.lf, -g.track_front / 2)  # y left
    assert rl == (-g.lr, g.track_rear / 2) and rr == (-g.lr, -g.track_rear / 2)  # x forward


def test_a_loaded_radius_is_the_free_radius_less_the_static_deflection(vehicle):
    loads = static_loads(vehicle)
    radii = loaded_radii(vehicle.tyres, loads)
    t = vehicle.tyres
    assert radii[0] == t.radius_front - loads[0] / t.vertical_stiffness_front
    assert radii[3] == t.radius_rear - loads[3] / t.vertical_stiffness_rear
    free = (t.radius_front,) * 2 + (t.radius_rear,) * 2
    deflection = np.array(free) - np.array(radii)
    assert np.all((deflection > 0.0) & (deflection < 0.03))  # a car tyre: mm to a few cm


def test_the_rolling_radius_lies_a_third_of_the_deflection_below_the_free_one(vehicle):
    """R_e = R_0 - rho / 3 by hand (0.327 m less a third of 9 mm is 0.324 m, to 1e-15), so
    between the loaded radius (R_0 - rho) and the free one; the estimators' slip ratios
    and the plant's slip both roll on it."""
    assert abs(rolling_radius(0.327, 0.009) - 0.324) < 1e-15
    t = vehicle.tyres
    loads = static_loads(vehicle)
    deflection = loads[0] / t.vertical_stiffness_front
    assert loaded_radii(t, loads)[0] < rolling_radius(t.radius_front, deflection) < t.radius_front


def test_estimators_and_plant_read_the_same_wheels(vehicle):
    """Exact equality: one expression, evaluated the same way everywhere."""
    centres = wheel_centres(vehicle.geometry)
    assert vehicle_constants(vehicle).positions == centres
    imu = np.asarray(vehicle.geometry.imu_position[:2])
    np.testing.assert_array_equal(corner_positions(vehicle), np.array(centres) - imu)
    plant = corners(vehicle)
    assert tuple((c.x, c.y) for c in plant) == centres
    radii = loaded_radii(vehicle.tyres, static_loads(vehicle))
    np.testing.assert_array_equal(vehicle_constants(vehicle).radius, radii)
    cg = vehicle.geometry.cg_height
    assert tuple(c.z_static for c in plant) == tuple(r - cg for r in radii)
