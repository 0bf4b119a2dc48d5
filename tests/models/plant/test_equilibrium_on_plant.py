"""The estimators' equilibrium model (paper eq. 14-18 and the issue 9 terms) against the plant.

The plant integrates the full rigid-body and unsprung dynamics; its reference
loads must satisfy the quasi-static :math:`A x = b` up to what the model
leaves out. With the vehicle file's model terms (road frame, body inertia,
lever arm, hub accelerometers) the residual must fall against the paper's
model, row by row, on both bundled vehicles. Measured on clean logs (RMS,
paper -> terms, N / N m / N m; `python -m wheelload.studies.experiments.equilibrium_table`):

sports car  brake-in-turn  68 -> 4,   189 -> 36,  55 -> 39
            iso-dlc        64 -> 2,     5 -> 11,  57 -> 33
            hockenheim*   209 -> 13,  223 -> 69,  54 -> 59
suv         brake-in-turn 361 -> 15,  663 -> 109, 248 -> 170
            iso-dlc       451 -> 20,  109 -> 133, 548 -> 184
            hockenheim*   596 -> 28,  951 -> 218, 276 -> 187

(* the first 15 % of the lap; the test drives the first 5 %.)
"""

import functools

import numpy as np
import pytest

from wheelload.models import GRAVITY, load_vehicle
from wheelload.models.vehicle.file import example_vehicle_path
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import scenario_run
from wheelload.studies.drive.simulation import simulate
from wheelload.studies.experiments.equilibrium_residuals import (
    paper_model,
    residual_rms,
    suspension_residual_rms,
    suspension_residuals,
    with_terms,
)

VEHICLES = {
    "sports_car": example_vehicle_path(),
    "suv": example_vehicle_path().with_name("suv.toml"),
}
# A moment row the manoeuvre barely excites (paper residual below 150 N m,
# 1 % of the weight at a 1 m arm) may rise a little: the body-rate derivative
# is a filtered one and lags; allowed 30 N m.
QUIET_ROW = 150.0
QUIET_RISE = 30.0


@functools.cache
def clean_log(car, name):
    vehicle = load_vehicle(VEHICLES[car])
    return vehicle, simulate(vehicle, scenario_run(name, vehicle, Options(shorten=0.05))).frame


@pytest.mark.parametrize("car", sorted(VEHICLES))
@pytest.mark.parametrize("name", ["brake-in-turn", "iso-dlc", "hockenheim"])
def test_plant_residual_falls_with_the_model_terms(car, name):
    vehicle, frame = clean_log(car, name)
    paper = residual_rms(paper_model(vehicle), frame)
    terms = residual_rms(vehicle, frame)
    weight = vehicle.mass.total * GRAVITY
    # vertical: the road-frame rotation and hub accelerometers take out >= 80 %
    assert terms["vertical"] < 0.2 * paper["vertical"]
    assert terms["vertical"] < 0.003 * weight
    for row in ("pitch", "roll"):
        if paper[row] > QUIET_ROW:
            assert terms[row] < paper[row], (row, paper, terms)
        else:
            assert terms[row] < paper[row] + QUIET_RISE, (row, paper, terms)


def test_a_wrong_sign_is_caught():
    """The check can fail: the paper's printed +m h a_x sign gives a large pitch residual."""
    vehicle, frame = clean_log("sports_car", "brake-in-turn")
    flipped = frame.assign(ax=-frame["ax"])
    assert residual_rms(vehicle, flipped)["pitch"] > 5 * residual_rms(vehicle, frame)["pitch"]
    assert np.isfinite(list(residual_rms(vehicle, frame).values())).all()


@pytest.mark.parametrize("car", sorted(VEHICLES))
def test_plant_pseudo_measurement_error_falls_with_link_loads(car):
    """Roll-centre and anti-pitch link loads: the plant's links carry them.

    Measured (pooled RMS of z - F_ref, clean brake-in-turn): sports car 88.8 ->
    27.7 N, SUV 271.8 -> 132.3 N with the link loads alone.
    """
    vehicle, frame = clean_log(car, "brake-in-turn")
    paper = suspension_residual_rms(paper_model(vehicle), frame)
    links = suspension_residual_rms(
        with_terms(paper_model(vehicle), geometric_transfer=True), frame
    )
    assert links < 0.6 * paper


# Per wheel and summed [N]: what the model's load-proportional share of the tyre side
# forces leaves against the plant's load-sensitive tyres grows with the roll angle
# (sports car 0.9 deg, SUV 3.2 deg in this turn).
STEADY_TURN_TOLERANCE = {"sports_car": (25.0, 50.0), "suv": (50.0, 120.0)}


@pytest.mark.parametrize("car", sorted(VEHICLES))
def test_pseudo_measurement_matches_the_plant_in_a_steady_turn(car):
    """Steady 0.4 g left turn (brake-in-turn, 5-9 s): each wheel's mean z - F_ref and their
    sum within :data:`STEADY_TURN_TOLERANCE`.

    The plant's links pass each tyre's lateral force along the line through
    the roll centre (jacking beyond the axle couple) and its springs carry
    body-z force while the wheel load is along the road normal. Without the
    per-wheel tyre-force term the mean errors were sports car -37, -45, -53,
    -59 N (sum -193), SUV -174, -251, -192, -233 N (sum -849); with it 7, 10,
    2, 9 N (sum 28) and 11, 29, 13, 43 N (sum 96).
    """
    vehicle, frame = clean_log(car, "brake-in-turn")
    steady = ((frame["t"] >= 5.0) & (frame["t"] <= 9.0)).to_numpy()
    assert abs(frame["ay_cg"][steady].mean()) > 3.5  # the window is in the turn
    error = suspension_residuals(vehicle, frame)[steady].mean(axis=0)
    wheel, total = STEADY_TURN_TOLERANCE[car]
    assert np.all(np.abs(error) < wheel), error
    assert abs(error.sum()) < total, error


def test_kerb_strike_pseudo_measurement_falls_with_hub_accelerometers_and_stops():
    """wheel-lift: the inner wheels hit a 6 cm kerb; unsprung inertia and stops matter."""
    vehicle, frame = clean_log("sports_car", "wheel-lift")
    links = with_terms(paper_model(vehicle), geometric_transfer=True)
    without = suspension_residual_rms(links, frame)
    hub = suspension_residual_rms(with_terms(links, unsprung_inertia=True, stops=True), frame)
    assert hub < 0.7 * without
