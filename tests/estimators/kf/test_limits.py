"""Covariance limits on a plant log: sigma grows across a gap, extreme tuning stays finite.

The log is the ISO lane change simulated by the full-vehicle plant with the
standard sensor models (``run_scenario``, fixture ``dlc``); the reference loads are the
plant's.
"""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators import Sample, StepFlag, TwoStageKF
from wheelload.estimators.kf.tuning import with_filter_sigma
from wheelload.models import GRAVITY
from wheelload.studies.experiments.faults.fault_injection import pooled_rmse


def test_sigma_grows_across_a_gap(vehicle, dlc):
    """5 s and 1 h gaps: the filter's own sigma (sqrt P) after >= before, and covers the error
    (issue: 176 -> 8.5 N); the reported sigma stays finite and within the weight."""
    kf = TwoStageKF(vehicle)
    kf.tuning = with_filter_sigma(kf.tuning)
    reported = TwoStageKF(vehicle)
    gap_at = 700
    for gap in (5.0, 3600.0):
        t = dlc.t.copy()
        t[gap_at:] += gap
        estimate = kf.run(dataclasses.replace(dlc, t=t))
        before, after = estimate.std[gap_at - 1], estimate.std[gap_at]
        assert np.all(after >= before)
        error = np.abs(estimate.loads[gap_at] - dlc.reference[gap_at])
        assert np.all(error <= 3.0 * after)
        weight = vehicle.mass.total * GRAVITY
        assert np.all(after <= weight)
        sigma = reported.run(dataclasses.replace(dlc, t=t)).std
        assert np.all(np.isfinite(sigma)) and np.all((sigma >= 0) & (sigma <= weight))


@pytest.mark.parametrize(
    "tuning",
    [{"initial_std": 1e200}, {"initial_std": 1.2e6}, {"process_noise_density": 1e300}],
)
def test_extreme_tuning_never_breaks_the_filter(vehicle, dlc, tuning):
    """The covariance ceiling (m g)^2 and floor keep every step finite (issue 8, item 6)."""
    kf = TwoStageKF(vehicle.replace(filter=dataclasses.replace(vehicle.filter, **tuning)))
    estimate = kf.run(dlc)
    assert np.isfinite(estimate.loads).all() and np.isfinite(estimate.std).all()
    assert not np.any(estimate.flags & StepFlag.STEP_REJECTED)
    assert estimate.flags[0] & StepFlag.COVARIANCE_LIMITED
    # With q = 1e300 the filter follows the measurements alone: a few hundred N at worst.
    assert pooled_rmse(estimate.loads, dlc.reference) < 250.0
    state, sample = kf.initial_state(), Sample(d=dlc.d[0], v=dlc.v[0], acc=dlc.acc[0], vx=dlc.vx[0])
    state, one = kf.step(state, sample, 0.01)
    assert np.isfinite(one.loads).all() and np.all(np.diag(state.P) > 0)
