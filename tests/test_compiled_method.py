"""The compiled family methods run a log in chunks with the state carried: same numbers."""

import numpy as np
import pytest

from wheelload.estimators.family import compiled_method
from wheelload.estimators.family.road_angle import RoadAngleKF
from wheelload.estimators.registry import build
from wheelload.estimators.signals import read_log
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.commands.estimate import example_log_path


@pytest.mark.parametrize("name", ["ycoo", "umvf", "corner", "road-angle"])
def test_chunked_run_equals_one_pass(name, monkeypatch):
    vehicle = load_vehicle(example_vehicle_path())
    signals = read_log(example_log_path()).slice(0, 300)
    estimator = build(name, vehicle)
    whole = estimator.run(signals)
    monkeypatch.setattr(compiled_method, "CHUNK", 37)
    chunked = estimator.run(signals)
    assert np.array_equal(whole.loads, chunked.loads)
    assert np.array_equal(whole.residual, chunked.residual)
    assert np.array_equal(whole.flags, chunked.flags)


def test_chunked_road_angles_equal_one_pass(monkeypatch):
    kf = RoadAngleKF(load_vehicle(example_vehicle_path()))
    signals = read_log(example_log_path()).slice(0, 300)
    _, whole = kf.run_with_road_angles(signals)
    monkeypatch.setattr(compiled_method, "CHUNK", 41)
    _, chunked = kf.run_with_road_angles(signals)
    assert np.array_equal(whole, chunked)
