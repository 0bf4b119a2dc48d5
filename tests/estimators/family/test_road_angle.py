"""Road-angle KF (road-angle paper eq. 4-18): grade and bank recovered on the plant's logs.

The true angles are the road's, read at the plant's path position: a 20 %
grade is atan(0.2) = 11.31 deg; chicane-bank-30 is a 30 % bank,
atan(0.3) = 16.70 deg with the left edge higher (studies/drive/scenarios.py).
"""

import numpy as np
import pytest

from wheelload.estimators.family.road_angle import RoadAngleKF
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.protocol import Estimator
from wheelload.estimators.samples import step_through
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.scenarios import scenario_run


def angles_on(name: str):
    """Estimated and true (grade, bank) [deg] and time of a simulated log with sensor noise."""
    vehicle = load_vehicle(example_vehicle_path())
    result = run_scenario(name, example_vehicle_path())
    road = scenario_run(name, vehicle, Options()).road.surface
    s = result.truth.frame["s"].to_numpy()
    truth = np.degrees(np.arctan(np.column_stack([np.interp(s, road.s, road.grade),
                                                  np.interp(s, road.s, road.bank)])))  # fmt: skip
    estimate, angles = RoadAngleKF(vehicle).run_with_road_angles(signals_from_frame(result.log))
    assert np.all(np.isfinite(estimate.loads)) and np.all(np.isfinite(angles))
    return np.degrees(angles), truth, result.truth.frame["t"].to_numpy()


def test_recovers_the_20_percent_grade_within_1_deg():
    estimate, truth, t = angles_on("slope-20")
    on_grade = t > 12.0  # full grade from t = 9 s; 3 s for the 1 s low-pass to settle
    assert on_grade.sum() > 500
    assert truth[on_grade, 0] == pytest.approx(np.degrees(np.arctan(0.2)), abs=1e-6)
    assert np.max(np.abs(estimate[on_grade, 0] - truth[on_grade, 0])) < 1.0
    assert np.max(np.abs(estimate[:, 1])) < 1.0  # no bank


def test_recovers_the_30_percent_bank_within_1_deg():
    """Mean over the weave within 1 deg; the unmeasured slip acceleration (up to 1.8 m/s^2)
    and the IMU's turn-on bias leave peaks of about 1 deg, bounded at 1.5 deg."""
    estimate, truth, t = angles_on("chicane-bank-30")
    settled = t > 8.0  # five stage time constants after the start
    assert truth[settled, 1] == pytest.approx(np.degrees(np.arctan(0.3)), abs=1e-6)
    error = estimate[settled, 1] - truth[settled, 1]
    assert abs(error.mean()) < 1.0
    assert np.max(np.abs(error)) < 1.5


def test_step_through_equals_run():
    from wheelload.estimators.logs.signals import read_log
    from wheelload.studies.pipeline.example_log import example_log_path

    signals = read_log(example_log_path()).slice(0, 150)
    kf = RoadAngleKF(load_vehicle(example_vehicle_path()))
    assert isinstance(kf, Estimator)
    run = kf.run(signals)
    assert np.array_equal(run.loads, step_through(kf, signals).loads)
    assert run.has_std and np.all(run.std > 0)


def test_body_inertia_comes_from_the_vehicle_file():
    """The SUV's file gives Ixx 850, Iyy 3600 kg m^2 (the sports car's 518.04, 1677): the
    filter's roll and pitch rows divide the suspension's roll / pitch stiffness by those
    plus m_s h^2 (axis on the ground), computed here from the file's numbers to 1e-9."""
    from wheelload.models.body_attitude import roll_pitch_stiffness
    from wheelload.models.family.road_angle import BodyInertia

    suv = load_vehicle(example_vehicle_path().with_name("suv.toml"))
    estimator = RoadAngleKF(suv)
    ixx, iyy, _ = suv.mass.inertia
    assert (estimator.inertia.roll, estimator.inertia.pitch) == (ixx, iyy) == (850.0, 3600.0)
    k = roll_pitch_stiffness(suv)
    arm_inertia = suv.mass.sprung * suv.geometry.cg_height**2
    assert estimator.A[1, 0] == pytest.approx(-k.roll / (ixx + arm_inertia), rel=1e-9)
    assert estimator.A[3, 2] == pytest.approx(-k.pitch / (iyy + arm_inertia), rel=1e-9)
    sports = BodyInertia(roll=518.04, pitch=1677.0)  # the constants it used to take
    assert not np.allclose(RoadAngleKF(suv, inertia=sports).A, estimator.A)
    # A body inertia given without an axis height has its axis on the ground too.
    assert RoadAngleKF(suv, inertia=sports).A[1, 0] == pytest.approx(
        -k.roll / (518.04 + arm_inertia), rel=1e-9
    )
