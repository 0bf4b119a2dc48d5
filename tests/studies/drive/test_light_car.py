"""A Formula Student car (284 kg, 1.53 m wheelbase, 1.2 m tracks) from a file that states only
its own values: read without --allow-unusual, simulated by the plant and estimated.

The file (``data/formula_student.toml``) sets none of the defaults that scale with the car;
before they were derived from its mass, ``filter.sigma_no_travel_az`` (then 288.4 N per m/s^2)
and ``filter.payload.mass_std`` (300 kg) exceeded its mass and the file was refused.
"""

from pathlib import Path

import numpy as np
import pytest

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.models import load_vehicle
from wheelload.models.runtime.toml_file import read_toml
from wheelload.models.vehicle.file import VEHICLE_FILE, example_vehicle_path
from wheelload.models.vehicle.scaled_defaults import CALIBRATED_MASSES, MASS_POWERS
from wheelload.studies.drive.scenario_runner import run_scenario

FILE = Path(__file__).parent / "data" / "formula_student.toml"


def _value(vehicle, key):
    node = vehicle
    for part in key:
        node = getattr(node, part)
    return node


def test_the_file_states_none_of_the_scaled_defaults():
    table = read_toml(FILE, VEHICLE_FILE)
    for key in MASS_POWERS:
        node = table
        for part in key[:-1]:
            node = node.get(part, {})
        assert key[-1] not in node, key


def test_the_scaled_defaults_follow_the_mass():
    """Each default is the fitted one times (m / 1613.2 kg)^k below the lighter fitted car
    (independent arithmetic on the files' values); the two fitted cars keep the fitted
    values (the dataclass defaults)."""
    light, sports = load_vehicle(FILE), load_vehicle(example_vehicle_path())
    suv = load_vehicle(example_vehicle_path().with_name("suv.toml"))
    assert (sports.mass.total, suv.mass.total) == CALIBRATED_MASSES
    ratio = light.mass.total / CALIBRATED_MASSES[0]
    for key, power in MASS_POWERS.items():
        fitted = _value(sports, key)
        assert _value(suv, key) == fitted, key
        np.testing.assert_allclose(
            _value(light, key), np.asarray(fitted) * ratio**power, rtol=1e-12
        )
    assert light.filter.sigma_no_travel_az == pytest.approx(307.7 * 284.0 / 1613.2)
    assert light.filter.payload.mass_std == pytest.approx(300.0 * 284.0 / 1613.2)


@pytest.mark.heavy(60)
def test_the_light_car_runs_on_its_plant_log():
    """The lane change on the plant with the file's car, the two-stage KF from the same
    file: pooled RMSE below 3 % of the mean reference load (measured 1.6 %; the sports car's
    lane change: 0.6 %), no NaN."""
    result = run_scenario("iso-dlc", FILE)
    signals = signals_from_frame(result.log, source="formula_student iso-dlc")
    estimate = TwoStageKF(load_vehicle(FILE)).run(signals)
    assert np.isfinite(estimate.loads).all()
    error = estimate.loads - signals.reference
    rmse = float(np.sqrt(np.mean(error**2)))
    assert rmse < 0.03 * float(np.mean(signals.reference))
