"""Full-lap scenarios: track data, the lap speed profile and the driver on lap segments."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.signal import butter, sosfiltfilt

from wheelload.models import GRAVITY
from wheelload.models.plant.dynamics import vehicle_plant
from wheelload.studies.drive import tracks
from wheelload.studies.drive.laps import GRIP_MARGIN
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import SCENARIOS, scenario_run
from wheelload.studies.drive.simulation import simulate
from wheelload.studies.drive.speed_profile import cornering_friction, lap_speed_profile


def _lap(road):
    inside = (road.s >= 0.0) & (road.s < road.length)
    return road.s[inside], inside


@pytest.mark.parametrize(
    ("name", "length", "max_grade"),
    # Lengths from the data README (4.57 km, 20.72 km) to 0.5 %; grades: Hockenheim is
    # within +-5 m of flat (a few per cent at most), Nordschleife grades reach about +-12 %
    # (upper bound 15 % for the smoothed GPS data, lower bound 8 % so smoothing keeps them).
    [("hockenheim", 4570.0, (0.0, 0.05)), ("nordschleife", 20720.0, (0.08, 0.15))],
)
def test_track_length_closure_and_grades(name, length, max_grade):
    road = getattr(tracks, name)()
    assert road.length == pytest.approx(length, rel=0.005)
    s, inside = _lap(road)
    # Closed clockwise loop: the heading turns by -2 pi over one lap (0.05 rad: the
    # 5 m Gaussian on the curvature), and the lead-out repeats the lap's start.
    turn = np.trapezoid(road.surface.curvature[inside], s)
    assert turn == pytest.approx(-2.0 * np.pi, abs=0.05)
    for column in (road.x, road.y, road.surface.elevation, road.surface.curvature):
        np.testing.assert_allclose(
            np.interp(s[1:200] + road.length, road.s, column), column[inside][1:200], atol=1e-3
        )  # 1 mm: the lead-out grid is offset by the fraction of a metre in the lap length
    grade = np.abs(road.surface.grade[inside])
    assert max_grade[0] <= grade.max() <= max_grade[1]
    assert np.all(road.half_width > 3.0)


def test_speed_profile_respects_its_limits(vehicle):
    road = tracks.hockenheim()
    speed = lap_speed_profile(vehicle, road, margin=GRIP_MARGIN)
    s, inside = _lap(road)
    v = speed[inside]
    mu_g = GRIP_MARGIN * cornering_friction(vehicle) * GRAVITY
    lateral = v**2 * np.abs(road.surface.curvature[inside])
    # Lift only lowers the corner limit; the vertical curvature of Hockenheim's
    # smoothed elevation (|z''| < 1e-4 1/m) may raise it by well under 1 %.
    assert lateral.max() <= 1.01 * mu_g
    # Tyre force per unit mass along the path: d(v^2/2)/ds plus drag, grade and rolling.
    m, aero = vehicle.mass.total, vehicle.aero
    drag = 0.5 * aero.air_density * aero.reference_area * aero.drag_coefficient * v**2 / m
    grade = road.surface.grade[inside]
    rolling = vehicle_plant(vehicle).tyre.rolling_resistance * GRAVITY
    tyre = np.gradient(0.5 * v**2, s) + drag + GRAVITY * grade / np.hypot(1, grade) + rolling
    ellipse = mu_g * np.sqrt(np.clip(1.0 - (lateral / mu_g) ** 2, 0.0, 1.0))
    # The passes apply the ellipse of one grid point to the step to the next, and
    # np.gradient averages two steps: compare with the larger ellipse of the
    # neighbours, 2 % of mu g for rounding.
    nearby = np.maximum.reduce([ellipse, np.roll(ellipse, 1), np.roll(ellipse, -1)])
    assert np.all(np.abs(tyre) <= nearby + 0.02 * mu_g)
    assert speed[inside][0] == pytest.approx(speed[inside][-1], rel=0.01)  # periodic


def _stays_on_track(vehicle, frame):
    # The whole car on the road: centre offset plus half the body width inside the
    # half-width, with 0.5 m to spare.
    half_body = 0.5 * vehicle_plant(vehicle).body.width
    margin = frame["half_width"] - (np.abs(frame["n"]) + half_body)
    assert margin.min() > 0.5


def test_hockenheim_opening_segment_stays_on_track(vehicle):
    # The first 1.5 km: full power onto the Nordkurve and the braking zone that made
    # the earlier driver spin (rear lock with a fixed brake split).
    run = scenario_run("hockenheim", vehicle, Options(shorten=1500.0 / 4570.0))
    frame = simulate(vehicle, run, internal_rate=500.0, output_rate=100.0).frame
    assert frame["s"].iloc[-1] >= run.stop - 1.0
    _stays_on_track(vehicle, frame)
    assert np.abs(frame["ay"]).max() > 7.0  # a real lap pace, above 0.7 g


def test_nordschleife_steep_stretch_stays_on_track(vehicle):
    road = tracks.nordschleife()
    s, inside = _lap(road)
    steep = float(s[np.argmax(np.abs(road.surface.grade[inside]))])
    base = scenario_run("nordschleife", vehicle, Options(shorten=0.1))
    run = dataclasses.replace(
        base, start=steep - 800.0, stop=steep + 700.0, record_from=None, max_time=120.0
    )
    frame = simulate(vehicle, run, internal_rate=500.0, output_rate=100.0).frame
    assert frame["s"].iloc[-1] >= run.stop - 1.0
    _stays_on_track(vehicle, frame)


def test_laps_are_registered():
    assert {"hockenheim", "nordschleife"} <= set(SCENARIOS)


def test_hockenheim_hairpin_steers_without_a_limit_cycle(vehicle):
    # The Spitzkehre hairpin (s = 1950-2150 m, 12-13 m/s at about 1 g). On the
    # track polyline the driver's steer oscillated at u / 5 m = 2.7 Hz with a
    # 1.5-25 Hz RMS of 1.5 deg (road wheel) and 0.46 m path error; on the plant's
    # own centre line 0.03 deg and 0.46 m. Bounds: 0.15 deg (5x the measured
    # value, a tenth of the limit cycle) and 0.6 m.
    base = scenario_run("hockenheim", vehicle, Options(shorten=0.1))
    run = dataclasses.replace(base, start=1950.0, stop=2150.0, record_from=None, max_time=30.0)
    frame = simulate(vehicle, run, internal_rate=500.0, output_rate=100.0).frame
    assert frame["s"].iloc[-1] >= run.stop - 1.0
    band = butter(4, [1.5, 25.0], btype="band", fs=100.0, output="sos")
    steer = sosfiltfilt(band, np.degrees(frame["steer"].to_numpy()))
    settled = frame["t"].to_numpy() > 1.0  # past the filter's start transient
    assert np.sqrt(np.mean(steer[settled] ** 2)) < 0.15
    assert np.abs(frame["n"] - frame["target"]).max() < 0.6
