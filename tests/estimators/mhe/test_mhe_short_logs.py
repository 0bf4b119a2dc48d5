"""The hard MHE on any short plausible log solves every sample (no fallback to its KF).

A fallback means an input missing or a solve failed. Before the fix a sample whose
equilibrium cannot be met with loads in bounds (a lift-off: small az with a large ay;
the warp interval collapses to its midpoint) fell back although nothing was missing:
the midpoint's loads, outside the bounds by design, failed the in-bounds check.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import Constraint, MheSettings
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.types import Signals

ESTIMATORS = {}


def estimator(vehicle, horizon: int, bounded: bool) -> MovingHorizonEstimator:
    key = (horizon, bounded)
    if key not in ESTIMATORS:
        settings = MheSettings(horizon=horizon, constraint=Constraint.HARD, bounded=bounded)
        ESTIMATORS[key] = MovingHorizonEstimator(vehicle, settings)
    return ESTIMATORS[key]


def plausible_log(draw, n: int) -> Signals:
    """``n`` samples inside the KF's plausible ranges (|a| <= 2.5 g, |d| <= 5 cm, ...)."""

    def floats(low, high, shape):
        values = draw(st.lists(st.floats(low, high), min_size=int(np.prod(shape)),
                               max_size=int(np.prod(shape))))  # fmt: skip
        return np.array(values).reshape(shape)

    dt = floats(0.001, 0.05, (n,))
    acc = floats(-15.0, 15.0, (n, 3))
    acc[:, 2] = floats(0.0, 24.0, (n,))  # az from near free fall to 2.5 g
    return Signals(t=np.cumsum(dt), vx=floats(0.0, 60.0, (n,)), acc=acc,
                   d=floats(-0.05, 0.05, (n, 4)), v=floats(-1.0, 1.0, (n, 4)))  # fmt: skip


@pytest.mark.parametrize("bounded", [False, True])
@seed(21)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow,
          HealthCheck.function_scoped_fixture])  # fmt: skip
@given(data=st.data(), horizon=st.integers(1, 4), n=st.integers(2, 6))
def test_hard_mhe_on_a_short_plausible_log_never_falls_back(vehicle, bounded, data, horizon, n):
    log = plausible_log(data.draw, n)
    mhe = estimator(vehicle, horizon, bounded)
    estimate = mhe.run(log)
    assert np.isfinite(input_matrix(log)[:12]).all()  # nothing missing
    assert not estimate.fallback.any(), (estimate.status, estimate.fallback)
    assert np.all(estimate.status == 1)
    assert np.isfinite(estimate.loads).all()
    if bounded:
        assert estimate.loads.min() >= 0.0
        # where the warp interval is not collapsed the equilibrium holds (hard constraint):
        u = input_matrix(log)
        terms = mhe.terms.map(n)(u, np.ones_like(u), sample_intervals(log.t)[None],
                                 np.zeros((4, n)), mhe.p, mhe.tuning, 1.0)  # fmt: skip
        lower, upper, b = (np.asarray(terms[i]) for i in (4, 5, 6))
        open_ = lower.ravel() < upper.ravel()
        residual = b.T - estimate.loads @ mhe.A.T
        # the hard window's own check: loads at A^+ b + n w to rounding (1e-6 of |b|)
        scale = np.abs(b.T).max(axis=1, keepdims=True)
        assert np.all(np.abs(residual[open_]) <= 1e-6 * scale[open_])
