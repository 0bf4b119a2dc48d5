"""IMU-only road frame: body attitude from the quasi-static equilibrium, on real plant logs."""

import casadi as ca
import numpy as np
import pytest

from wheelload.estimators import StepFlag, signals_from_frame
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import ModelParameters, example_vehicle_path, load_vehicle
from wheelload.models.body_attitude import attitude_from_equilibrium, attitude_travel
from wheelload.models.conventions import WHEELS
from wheelload.models.terms import attitude_from_deflection
from wheelload.studies.drive.scenario_runner import run_scenario

TRAVEL = [f"{kind}_{w}" for kind in ("d", "v") for w in WHEELS]
SUV = example_vehicle_path().parent / "suv.toml"


def _attitude(frame, p):
    """Body roll and pitch relative to the road of :func:`attitude_from_equilibrium`
    (tyre deflection added as for the travels) for each sample's specific force."""
    f = ca.SX.sym("f", 3)
    travel = attitude_travel(*attitude_from_equilibrium(f, p), p)
    phi, theta, _ = attitude_from_deflection(travel, p)
    mapped = ca.Function("attitude", [f], [phi, theta]).map(len(frame))
    return [np.asarray(x).ravel() for x in mapped(frame[["ax", "ay", "az"]].to_numpy().T)]


@pytest.mark.parametrize("path", [example_vehicle_path(), SUV], ids=["sports_car", "suv"])
def test_quasi_static_attitude_against_the_plant(path):
    # ISO 8855: a left turn (a_y > 0) rolls the body to the right (phi > 0, right side
    # down). Steady turn of brake-in-turn, clean signals, against the plant's own phi
    # relative to the road: mean roll within 15 % (measured 8 % sports car, 2 % SUV; the
    # model leaves out the unsprung roll and the links' jacking); pitch error RMS below
    # 0.4 of the pitch's RMS (measured 0.23, 0.34).
    truth = run_scenario("brake-in-turn", path, noise=0.0).truth.frame
    phi, theta = _attitude(truth, ModelParameters.from_vehicle(load_vehicle(path)))
    turn = truth["ay"].to_numpy() > 3.0
    assert turn.sum() > 500
    plant_phi = truth["phi"].to_numpy()[turn]
    assert (plant_phi > 0).all() and (phi[turn] > 0).all()
    assert abs(phi[turn].mean() / plant_phi.mean() - 1) < 0.15
    plant_theta = truth["theta"].to_numpy()
    assert np.sqrt(np.mean((theta - plant_theta) ** 2)) < 0.4 * np.sqrt(np.mean(plant_theta**2))


# vehicle, scenario, noise scale; mean |total load error| in the turn, before -> after the
# road frame without travel: 102 -> 9 N, 561 -> 22 N, 192 -> 18 N.
TURNS = [
    (example_vehicle_path(), "brake-in-turn", 0.0),
    (SUV, "brake-in-turn", 0.0),
    (example_vehicle_path(), "accel-in-turn", 1.0),
]


@pytest.mark.parametrize(("path", "name", "noise"), TURNS, ids=["sports", "suv", "sports-noisy"])
def test_imu_only_total_load_in_a_turn(path, name, noise):
    # Issue goal: the sum of the four loads within 100 N of the reference in a turn.
    log = run_scenario(name, path, noise=noise).log
    signals = signals_from_frame(log.drop(columns=TRAVEL), source=name)
    estimate = TwoStageKF(load_vehicle(path)).run(signals)
    turn = np.abs(log["ay"].to_numpy()) > 3.0
    total = (estimate.loads - signals.reference).sum(axis=1)
    assert turn.sum() > 300
    assert np.abs(total[turn]).mean() < 100.0
    # The reported sigma of a wheel without travel (sigma_no_travel*, fitted by `bench
    # discernment --fit-no-travel` on IMU-only logs as logged and with ay 0.5 s late, so
    # that a real car's front-only reference log is covered): +-2 sigma covers the errors
    # after the first second (measured 99.99 %, 99.97 %, 100 %); RMS sigma 1-10x the RMSE
    # (measured 8.8, 6.5 and 4.5x; 1.5-4.3x before the late-ay calibration): on the plant's
    # own logs, whose ay is on time, the |ay - vx wz| term over-covers a turn.
    settled = signals.t - signals.t[0] >= 1.0
    error = (estimate.loads - signals.reference)[settled]
    sigma = estimate.std[settled]
    assert np.mean(np.abs(error) <= 2 * sigma) >= 0.95
    ratio = np.sqrt(np.mean(sigma**2)) / np.sqrt(np.mean(error**2))
    assert 1.0 <= ratio <= 10.0
    # The road frame stays on, flagged with the bit of a term without its input.
    assert (estimate.flags & StepFlag.ROAD_FRAME_OR_LINKS_DROPPED).all()
