"""Every registered method on plant logs: the ISO double lane change and a stretch of Hockenheim.

Against the plant's reference loads, pooled RMSE % (Siegloff & Choi eq. 27-28). Sign
or unit errors give tens of percent; the paper's own spread on Hockenheim (Table IV)
is 1.9-10.9 % per wheel. Measured on these two logs (full model / paper model,
iso-dlc and the stretch): kf 0.68 / 0.94; D 0.71 / 0.82 against 2.13 / 6.58 with the
paper's model, E 0.82 / 1.00, E+C 0.74 / 1.01, F 1.10 / 1.46, ycoo 0.82 / 1.03, umvf
1.04 / 1.29, road-angle 0.69 / 0.82, C 0.98 / 2.32, B 1.86 / 2.74, corner 1.90 / 4.48;
C-paper (full model only) 1.88 / 4.86.
"""

import numpy as np
import pytest

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.protocol import SuspensionModel
from wheelload.estimators.registry import build, method, methods
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.metrics import wheel_metrics

# The full lap (14 000 samples) is in the closing note's table; here 8 % of it (~11 s).
LAP_SHARE = 0.08
#: Pooled RMSE % bound on the full model: the measured value (module docstring) with a
#: margin of about 50 % for numerical and plant changes. Methods that take the
#: pseudo-measurement 2 %; C (no travel) 3 %; B (static lateral split) 4 %; corner (IMU
#: attitude only, no pseudo-measurement) 6.5 %; C-paper (static loads and rigid-body
#: transfer with the static axle split, no vertical acceleration or aero) 7.5 %.
BOUND = {"B": 4.0, "C": 3.5, "corner": 6.5, "C-paper": 7.5}
DEFAULT_BOUND = 2.0
#: The paper's bare model misses the load the plant's roll centres and anti-pitch links
#: carry (measured up to 7.0 % on the stretch): every method inside 8 %.
PAPER_BOUND = 8.0
#: Methods whose estimate rests on the pseudo-measurement: on the Hockenheim stretch the
#: full model at most 0.35 of the paper model's error (measured 0.12-0.27).
PSEUDO_MEASUREMENT = ("D", "E", "E+C", "F", "ycoo", "umvf", "road-angle")


@pytest.fixture(scope="module")
def logs():
    path = example_vehicle_path()
    dlc = run_scenario("iso-dlc", path).log
    lap = run_scenario("hockenheim", path, options=Options(shorten=LAP_SHARE)).log
    return {
        "iso-dlc": signals_from_frame(dlc, source="iso-dlc"),
        "hockenheim": signals_from_frame(lap, source="hockenheim"),
    }


def pooled(estimator, signals) -> float:
    estimate = estimator.run(signals)
    assert estimate.loads.shape == (len(signals), 4)
    for array in (estimate.loads, estimate.std, estimate.residual):
        assert np.all(np.isfinite(array))
    assert not np.any(estimate.flags), "no input is missing"
    return wheel_metrics(estimate.loads, signals.reference).loc["pooled", "RMSE %"]


@pytest.mark.parametrize("name", list(methods()))
def test_method_on_plant_logs_within_its_bound(name, logs):
    vehicle = load_vehicle(example_vehicle_path())
    full = {log: pooled(build(name, vehicle), signals) for log, signals in logs.items()}
    for log, value in full.items():
        assert value < BOUND.get(name, DEFAULT_BOUND), f"{name} on {log}: {value:.2f} %"
    if not method(name).model_choice:
        return
    estimator = build(name, vehicle, SuspensionModel.PAPER)
    paper = {log: pooled(estimator, signals) for log, signals in logs.items()}
    for log, value in paper.items():
        assert value < PAPER_BOUND, f"{name} (paper model) on {log}: {value:.2f} %"
    if name in PSEUDO_MEASUREMENT:
        ratio = full["hockenheim"] / paper["hockenheim"]
        assert ratio < 0.35, f"{name}: full / paper model on the stretch {ratio:.2f}"
