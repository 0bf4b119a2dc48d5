"""Every registered method on plant logs: the ISO double lane change and a stretch of Hockenheim."""

import numpy as np
import pytest

from wheelload.estimators.registry import build, methods
from wheelload.estimators.signals import signals_from_frame
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.metrics import wheel_metrics
from wheelload.studies.scenario_runner import run_scenario
from wheelload.studies.scenarios import Options

# The full lap (14 000 samples) is in the closing note's table; here 8 % of it (~11 s).
LAP_SHARE = 0.08


@pytest.fixture(scope="module")
def logs():
    path = example_vehicle_path()
    dlc = run_scenario("iso-dlc", path).log
    lap = run_scenario("hockenheim", path, options=Options(shorten=LAP_SHARE)).log
    return {
        "iso-dlc": signals_from_frame(dlc, source="iso-dlc"),
        "hockenheim": signals_from_frame(lap, source="hockenheim"),
    }


@pytest.mark.parametrize("name", list(methods()))
def test_method_runs_on_plant_logs_with_finite_output(name, logs):
    vehicle = load_vehicle(example_vehicle_path())
    estimator = build(name, vehicle)
    for log, signals in logs.items():
        estimate = estimator.run(signals)
        assert estimate.loads.shape == (len(signals), 4)
        for array in (estimate.loads, estimate.std, estimate.residual):
            assert np.all(np.isfinite(array)), f"{name} on {log}"
        assert not np.any(estimate.flags), f"{name} on {log}: no input is missing"
        # Sign or unit errors give tens of percent; the paper's own spread on Hockenheim
        # (Table IV) is 1.9-10.9 % per wheel. Every method must stay inside 8 % pooled
        # (was 6 %): the family methods use the paper's spring-only model, and the plant
        # now passes part of the load transfer through roll centres and anti-pitch links,
        # which that model lacks (measured on this stretch: 6.5-7.0 % for D, E, F, ycoo,
        # umvf and road-angle; the two-stage KF with the model terms stays far below).
        pooled = wheel_metrics(estimate.loads, signals.reference).loc["pooled", "RMSE %"]
        assert pooled < 8.0, f"{name} on {log}: pooled RMSE {pooled:.2f} %"
