"""The estimators' equilibrium model (paper eq. 14-18) against the independent plant.

The plant integrates the full rigid-body and unsprung dynamics; its reference
loads must satisfy the quasi-static :math:`A x = b` up to the inertia terms
the model leaves out (body pitch/roll acceleration, unsprung heave), i.e. far
better than a model with a wrong sign would. Measured on clean logs: residual
RMS 76 / 216 / 63 (brake-in-turn) and 123 / 141 / 71 (slope-20) in N, N m,
N m, against moment swings of 1134-1256 N m and a weight of 15.8 kN; the
same log with the sign of the a_x term flipped gives a pitch residual of
2393 N m (brake-in-turn).
"""

import numpy as np
import pytest

from wheelload.models import GRAVITY, ModelParameters, equilibrium_function
from wheelload.studies.scenarios import scenario_run
from wheelload.studies.simulation import simulate


@pytest.mark.parametrize("name", ["brake-in-turn", "slope-20"])
def test_plant_loads_satisfy_the_equilibrium_model(vehicle, name):
    frame = simulate(vehicle, scenario_run(name, vehicle)).frame
    acc = frame[["ax", "ay", "az"]].to_numpy()
    loads = frame[["fz_fl", "fz_fr", "fz_rl", "fz_rr"]].to_numpy()
    p = ModelParameters.from_vehicle(vehicle).vector()
    A, b = equilibrium_function().map(len(frame))(acc.T, frame["vx"].to_numpy()[None, :], p)
    A, b = np.asarray(A)[:, :4], np.asarray(b).T
    residual = np.sqrt(np.mean((loads @ A.T - b) ** 2, axis=0))
    swing = np.sqrt(np.mean((b - b.mean(axis=0)) ** 2, axis=0))
    weight = vehicle.mass.total * GRAVITY
    assert residual[0] < 0.015 * weight  # vertical: unsprung heave and bump inertia, < 1.5 %
    moving = swing[1:] > 500.0  # N m: the moment rows this manoeuvre really excites
    assert moving.any()
    # pitch and roll: the residual (inertia left out) stays below 35 % of the swing
    assert np.all(residual[1:][moving] < 0.35 * swing[1:][moving])
