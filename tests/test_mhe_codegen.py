"""The generated embedded MHE (OSQP embedded C + CasADi sample routine) equals the Python MHE."""

import shutil

import numpy as np
import pytest

from wheelload.estimators.mhe import Arrival, Constraint, MheSettings, MovingHorizonEstimator
from wheelload.estimators.mhe_codegen import build_mhe_library
from wheelload.studies.synthetic import SensorNoise, steady_cornering, synthetic_log

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")


@pytest.fixture(scope="module")
def wheel_lift(vehicle):
    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    return synthetic_log(vehicle, steady_cornering(ay=15.0, duration=2.0), noise=noise, seed=7)


@pytest.mark.parametrize("bounded", [False, True])
@pytest.mark.parametrize("constraint", list(Constraint))
def test_generated_c_equals_python(vehicle, wheel_lift, tmp_path, constraint, bounded):
    settings = MheSettings(
        horizon=10, constraint=constraint, bounded=bounded, arrival=Arrival.STEADY_STATE
    )
    library = build_mhe_library(vehicle, settings, tmp_path, dt=0.01)
    c = library.run(wheel_lift)
    python = MovingHorizonEstimator(vehicle, settings).run(wheel_lift)
    assert np.all(c.status == 1)
    # the same ADMM iterations in C and Python; a tenth of the 1e-6 kN tolerance x 1e3
    np.testing.assert_allclose(c.loads, python.loads, rtol=0, atol=0.1)
    if bounded:
        assert c.loads.min() >= 0.0
