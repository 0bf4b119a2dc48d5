"""The embedded MHE's robust losses, bias states, lagged output and linked KF equal the Python MHE.

Each generated C is compiled with gcc, loaded and run on the bundled plant log
(a 20 mm spike on the front-left travel sensor, a 4 mm offset on the rear-left
one, a three-sample dropout of the front-right one) beside the Python MHE with
the settings the C realises (:func:`embedded_settings`). Row k of the C is the
estimate of sample k - lag, row i of the Python run that of sample i.
"""

import dataclasses

import numpy as np
import pytest
from c_parity import assert_c_equals_python, mhe_library, needs_gcc

from wheelload.estimators import read_log
from wheelload.estimators.codegen.mhe import embedded_settings
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import (
    BiasStates,
    Constraint,
    Loss,
    MheSettings,
    ResidualLoss,
    SolverSettings,
)
from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.example_log import example_log_path

pytestmark = needs_gcc

HUBER = ResidualLoss(kind=Loss.HUBER, threshold=2.0)
BOTH = BiasStates.TRAVEL | BiasStates.ACCELERATION
#: Both sides solve to 1e-9 kN, so they agree far below a newton whatever the ADMM path.
TIGHT = SolverSettings(eps_abs=1e-9, eps_rel=1e-9, max_iter=20000)
CASES = {
    "soft-huber-l1-bias-lag-2": MheSettings(
        horizon=6,
        bounded=True,
        suspension_loss=HUBER,
        constraint_loss=ResidualLoss(kind=Loss.L1),
        bias_states=BOTH,
        lag=2,
    ),  # fmt: skip
    "hard-travel-bias-huber-lag-2": MheSettings(
        horizon=6,
        bounded=True,
        constraint=Constraint.HARD,
        bias_states=BiasStates.TRAVEL,
        suspension_loss=HUBER,
        lag=2,
    ),  # fmt: skip
    "quadratic-lag-3": MheSettings(horizon=6, bounded=True, lag=3),
}


@pytest.fixture(scope="module")
def faulted_log():
    signals = read_log(example_log_path()).slice(300, 600)
    d = signals.d.copy()
    d[100:104, 0] += 0.02  # spike
    d[:, 2] += 0.004  # ride-height offset
    d[200:203, 1] = np.nan  # a dropout: its rows are dropped and flagged
    return dataclasses.replace(signals, d=d)


def run_both(vehicle, signals, settings, precision, folder):
    c = mhe_library(
        vehicle, settings, folder, 0.01, precision, vehicle_path=example_vehicle_path()
    ).run(signals)
    realised = embedded_settings(settings, filter_linked=True, precision=precision)
    python = MovingHorizonEstimator(vehicle, realised).run(signals)
    lag = settings.lag
    return c, python, lag, len(signals) - lag


@pytest.mark.parametrize("name", list(CASES))
def test_double_c_equals_python(vehicle, faulted_log, tmp_path, name):
    settings = dataclasses.replace(CASES[name], solver=TIGHT)
    c, python, lag, n = run_both(vehicle, faulted_log, settings, Precision.DOUBLE, tmp_path)
    assert np.all(c.status == 1) and not c.fallback.any()
    np.testing.assert_array_equal(c.flags, python.flags)
    assert c.flags[201] != 0
    # tolerance 0.01 N on loads and 0.05 on the residuals [N, N m] (loads measured <= 1.9e-3 N
    # soft Huber/L1, 8e-7 N hard: the solvers' 1e-9 tolerance, see the ride-height test)
    assert_c_equals_python(c.loads[lag:], python.loads[:n], rtol=0, atol=0.01)
    assert_c_equals_python(c.residual[lag:], python.residual[:n], rtol=0, atol=0.05)
    # the linked filter's (soft: two-stage KF, hard: projection KF): the same arithmetic
    assert_c_equals_python(c.std, python.std, rtol=1e-9, atol=0)
    assert c.std.min() > 0.0
    if settings.bias_states != BiasStates.NONE:
        # reported: four travel offsets, then the accelerometer biases in use
        accelerations = len(settings.bias_states.acceleration_columns)
        assert c.bias.shape[1] == python.bias.shape[1] == 4 + accelerations
        # travel offsets: 1 um (measured 2e-8 m); ax/ay biases: 1e-4 m/s^2 (measured 6e-6)
        assert_c_equals_python(c.bias[:, :4], python.bias[:, :4], rtol=0, atol=1e-6)
        assert_c_equals_python(c.bias[:, 4:], python.bias[:, 4:], rtol=0, atol=1e-4)


def test_float_c_within_the_stated_bound(vehicle, faulted_log, tmp_path):
    """Huber suspension rows, both bias groups, lag 2, in float32 (OSQP at 1e-5).

    Against the window's exact minimiser (the double Python MHE at 1e-9): the
    bias states integrate each solve's tolerance, so the Python MHE itself is
    1.9 N (at 1e-6) and 7.0 N (at 1e-5) from it on this log.
    """
    settings = MheSettings(horizon=6, bounded=True, suspension_loss=HUBER, bias_states=BOTH, lag=2)
    c = mhe_library(
        vehicle, settings, tmp_path, 0.01, Precision.FLOAT, vehicle_path=example_vehicle_path()
    ).run(faulted_log)
    exact = MovingHorizonEstimator(vehicle, dataclasses.replace(settings, solver=TIGHT))
    python = exact.run(faulted_log)
    assert np.all(c.status == 1) and not c.fallback.any()
    np.testing.assert_array_equal(c.flags, python.flags)
    # stated bound 5 N (measured 2.8 N)
    assert np.abs(c.loads[2:] - python.loads[:-2]).max() < 5.0
    assert c.loads.min() >= 0.0


def test_ride_height_and_ay_bias_in_c_equal_python_to_a_micronewton(vehicle, faulted_log, tmp_path):
    """One offset per axle and the ay bias (``codegen --bias-states ride-height+ay``), Huber rows.

    Both solve to 1e-12: the C's arithmetic then agrees with Python's to 1e-6 N (measured
    6e-8 N); at 1e-9 the solvers' own tolerance leaves 7e-5 N, at the first samples.
    """
    exact = SolverSettings(eps_abs=1e-12, eps_rel=1e-12, max_iter=50000)
    settings = MheSettings(horizon=6, bounded=True, suspension_loss=HUBER, solver=exact,
                           bias_states=BiasStates.RIDE_HEIGHT | BiasStates.LATERAL)  # fmt: skip
    c, python, _, _ = run_both(vehicle, faulted_log, settings, Precision.DOUBLE, tmp_path)
    assert np.all(c.status == 1) and not c.fallback.any()
    np.testing.assert_array_equal(c.flags, python.flags)
    assert_c_equals_python(c.loads, python.loads, rtol=0, atol=1e-6)
    assert_c_equals_python(c.std, python.std, rtol=1e-9, atol=0)
    # four travel offsets (the two axles' ride heights) [m], then ay [m/s^2]
    assert c.bias.shape[1] == python.bias.shape[1] == 5
    assert_c_equals_python(c.bias[:, :4], python.bias[:, :4], rtol=0, atol=1e-9)
    assert_c_equals_python(c.bias[:, 4], python.bias[:, 4], rtol=0, atol=1e-9)
    assert np.all(c.bias[:, 0] == c.bias[:, 1]) and np.abs(c.bias[:, :4]).max() > 1e-4
