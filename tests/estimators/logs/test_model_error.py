"""The model-error channel (estimators/logs/model_error.py): a wrong vehicle file or a corner's
travel zero is named, sized and never blamed on a healthy sensor.

Plant logs of the sports car (the file the plant ran on is exact); each wrong file changes
one group of keys as the issue lists them. Tolerances: the fitted value against the
plant's own (exact) value, 10 % for springs, mass and a forgotten motion ratio (the
front axle's spring, damper and bar rates given at the damper, 1/0.7^2 times the wheel's:
the front spring rate fitted), 15 % for the bars (their
signature is shared with the roll-centre links the fit leaves as they are); a travel
zero within 1 mm (the travel sensors' own warp on these logs is up to 0.9 mm).
"""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.model_error import diagnose
from wheelload.studies.experiments.faults import fault_injection as fi

SCENARIOS = ("iso-dlc", "brake-in-turn")


def _axles(vehicle, **changes):
    suspension = vehicle.suspension
    for axle in ("front", "rear"):
        current = getattr(suspension, axle)
        new = {key: change(getattr(current, key)) for key, change in changes.items()}
        suspension = dataclasses.replace(suspension, **{axle: dataclasses.replace(current, **new)})
    return vehicle.replace(suspension=suspension)


def _mass(vehicle, factor):
    mass = vehicle.mass
    added = (factor - 1.0) * mass.sprung
    return vehicle.replace(
        mass=dataclasses.replace(mass, sprung=mass.sprung + added, total=mass.total + added)
    )


def _front_at_damper(vehicle, motion_ratio=0.7):
    """The front rates given at the damper: the wheel's over the motion ratio squared."""
    front = vehicle.suspension.front
    keys = ("spring_rate", "damper_push", "damper_pull", "arb_rate")
    at_damper = {key: getattr(front, key) / motion_ratio**2 for key in keys}
    return vehicle.replace(
        suspension=dataclasses.replace(
            vehicle.suspension, front=dataclasses.replace(front, **at_damper)
        )
    )


WRONG = {
    "no bars": (lambda v: _axles(v, arb_rate=lambda x: 0.0), "anti-roll bars", 0.15),
    "front motion ratio forgotten": (_front_at_damper, "front motion ratio", 0.10),
    "springs -20 %": (lambda v: _axles(v, spring_rate=lambda x: 0.8 * x), "springs", 0.10),
    "mass +20 %": (lambda v: _mass(v, 1.2), "mass", 0.10),
}


def pooled(estimate, signals):
    return float(np.sqrt(np.mean((estimate.loads - signals.reference) ** 2)))


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_the_exact_file_is_not_questioned(vehicle, plant_log, scenario):
    assert diagnose(plant_log(scenario), vehicle).finding is None
    assert TwoStageKF(vehicle).run(plant_log(scenario)).model_errors == ()


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("wrong", list(WRONG))
def test_a_wrong_file_is_named_sized_and_no_sensor_is_blamed(
    vehicle, plant_log, scenario, wrong, request
):
    """The finding names the group of keys (on the lane change springs and mass fit almost
    alike: the one not named is named as the rival) and its value is the plant's own
    within the tolerance; no channel is isolated; σ widens by the loads' change the
    finding (or its rival) implies, so that ±2σ covers at least 95 % of the error, σ
    at least twice the exact file's."""
    if wrong == "front motion ratio forgotten" and scenario == "brake-in-turn":
        request.applymarker(
            pytest.mark.xfail(
                strict=True,
                reason="d_fr is isolated: in a steady turn the front rates' error looks like "
                "a bias of the loaded front corner's travel (the gain/bias split is the "
                "accelerometers' only)",
            )
        )
    edit, name, tolerance = WRONG[wrong]
    signals = plant_log(scenario)
    estimate = TwoStageKF(edit(vehicle)).run(signals)
    (finding,) = estimate.model_errors
    assert name in (finding.name, finding.runner_up)
    truth = {
        "anti-roll bars": (vehicle.suspension.front.arb_rate, vehicle.suspension.rear.arb_rate),
        "springs": (vehicle.suspension.front.spring_rate, vehicle.suspension.rear.spring_rate),
        "mass": (vehicle.mass.total,),
        "front motion ratio": (vehicle.suspension.front.spring_rate,),
    }
    if finding.name == name:
        np.testing.assert_allclose(finding.fitted_value, truth[name], rtol=tolerance)
    assert finding.keys[0] in finding.message() and "not the sensors" in finding.message()
    assert estimate.faults.empty
    error = np.abs(estimate.loads - signals.reference)
    assert np.mean(error <= 2 * estimate.std) >= 0.95
    exact = TwoStageKF(vehicle).run(signals)
    assert estimate.std.mean() >= 2 * exact.std.mean()


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("channel, offset", [("d_fl", 3e-3), ("d_rr", -3e-3)])
def test_a_corner_travel_zero_is_found_and_taken_off(vehicle, plant_log, scenario, channel, offset):
    """One potentiometer not zeroed (±3 mm): named with its size, taken off for the run, and
    the error within 1.25 x the clean log's (without the check: 4-6 x)."""
    clean = plant_log(scenario)
    k = ("d_fl", "d_fr", "d_rl", "d_rr").index(channel)
    d = clean.d.copy()
    d[:, k] += offset
    shifted = dataclasses.replace(clean, d=d)
    estimate = TwoStageKF(vehicle).run(shifted)
    (finding,) = estimate.model_errors
    assert finding.keys == (channel,)
    assert finding.fitted_value[0] == pytest.approx(offset, abs=1e-3)
    assert estimate.faults.empty
    base = pooled(TwoStageKF(vehicle).run(clean), clean)
    assert pooled(estimate, shifted) <= 1.25 * base
    unchecked = TwoStageKF(vehicle, check_file=False).run(shifted)
    assert pooled(unchecked, shifted) > 3 * base


def test_a_stuck_sensor_is_a_fault_not_a_travel_zero(vehicle, plant_log):
    """A travel sensor stuck half-way through the lane change warps the travel from then on:
    the fault monitor isolates it, and the file check leaves the samples about the fault
    out and finds no zero (the warp before and after must agree for a zero)."""
    signals = plant_log("iso-dlc")
    fault = next(f for f in fi.FAULTS if f.name == "stuck")
    stuck = fault.inject(signals, int(fi.ONSET * len(signals)), np.random.default_rng(0))
    estimate = TwoStageKF(vehicle).run(stuck)
    assert list(estimate.faults["channel"]) == ["d_fl"]
    assert not any(f.name.startswith("travel zero") for f in estimate.model_errors)
