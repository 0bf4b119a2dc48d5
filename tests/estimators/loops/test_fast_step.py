"""The fast per-sample step (compiled C on preallocated buffers) equals the CasADi reference step.

:meth:`TwoStageKF.step` runs the step Function's own instructions as C
(:mod:`wheelload.estimators.loops.fast_step`), compiled without FMA contraction
(``-std=c99``), so it computes the same IEEE operations in the same order as
:meth:`TwoStageKF.reference_step` (CasADi's virtual machine): the test asks
for bit-identical state, outputs and flags, over a plant log with the guards
acting (outliers, missing channels, optional channels present and absent,
rejected intervals).
"""

import numpy as np
import pytest

from wheelload.estimators import Sample
from wheelload.estimators.kf.projection import ProjectionKF
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.protocol import sample_intervals


def samples_with_trouble(signals, n):
    """Samples of a plant log with outliers, missing values and optional channels."""
    rng = np.random.default_rng(12)
    dt = sample_intervals(signals.t)[:n].copy()
    dt[[50, 51, 90]] = (0.0, np.nan, -0.01)  # rejected intervals
    dt[120] = 0.25  # a gap
    samples = []
    for k in range(n):
        d, acc = signals.d[k].copy(), signals.acc[k].copy()
        if k % 37 == 5:
            d[rng.integers(4)] = np.nan
        if k % 53 == 7:
            acc[0] = 80.0  # implausible
        if k == 200:
            d[0] += 0.03  # innovation gate
        rates = np.array([0.01, -0.02, 0.1]) * np.sin(0.05 * k) if k % 2 else None
        hub = np.full(4, 9.81) + 0.5 * np.sin(0.3 * k) if k % 3 == 0 else None
        samples.append(Sample(d=d, v=signals.v[k], acc=acc, vx=signals.vx[k], rates=rates, hub=hub))
    return samples, dt


def assert_same(fast, reference):
    (state_f, est_f), (state_r, est_r) = fast, reference
    for a, b in ((state_f.x, state_r.x), (state_f.P, state_r.P), (state_f.m, state_r.m)):
        np.testing.assert_array_equal(a, b)
    for name in ("loads", "std", "residual", "flags"):
        np.testing.assert_array_equal(getattr(est_f, name), getattr(est_r, name), err_msg=name)
    assert est_f.flags.dtype == est_r.flags.dtype


@pytest.mark.parametrize("sample_interval", [None, 0.01])
def test_fast_step_is_bit_identical_to_the_casadi_step(vehicle, plant_log, sample_interval):
    kf = TwoStageKF(vehicle, sample_interval=sample_interval)
    samples, dt = samples_with_trouble(plant_log("iso-dlc"), 400)
    fast = reference = kf.initial_state()
    flags = 0
    for sample, interval in zip(samples, dt):
        one_fast = kf.step(fast, sample, interval)
        one_reference = kf.reference_step(reference, sample, interval)
        assert_same(one_fast, one_reference)
        (fast, estimate), (reference, _) = one_fast, one_reference
        flags |= int(estimate.flags[0])
    assert flags & 0xFF00, "the guards acted on this log"  # else the test checks too little


def test_fast_step_of_the_projection_filter(vehicle, plant_log):
    kf = ProjectionKF(vehicle)
    samples, dt = samples_with_trouble(plant_log("iso-dlc"), 130)
    fast = reference = kf.initial_state()
    for sample, interval in zip(samples, dt):
        one_fast = kf.step(fast, sample, interval)
        one_reference = kf.reference_step(reference, sample, interval)
        assert_same(one_fast, one_reference)
        fast, reference = one_fast[0], one_reference[0]


def test_returned_state_is_not_overwritten_by_the_next_step(vehicle, plant_log):
    kf = TwoStageKF(vehicle)
    samples, dt = samples_with_trouble(plant_log("iso-dlc"), 130)
    first, estimate = kf.step(kf.initial_state(), samples[0], dt[0])
    kept = first.x.copy(), first.P.copy(), estimate.loads.copy()
    kf.step(first, samples[1], dt[1])
    np.testing.assert_array_equal(first.x, kept[0])
    np.testing.assert_array_equal(first.P, kept[1])
    np.testing.assert_array_equal(estimate.loads, kept[2])


@pytest.mark.parametrize("sample_interval", [None, 0.01])
def test_live_filter_is_bit_identical_to_the_casadi_step(vehicle, plant_log, sample_interval):
    """The lean path (state kept in the compiled buffer, views returned) equals reference_step
    bit for bit, through Sample groups and through input vectors alike."""
    kf = TwoStageKF(vehicle, sample_interval=sample_interval)
    samples, dt = samples_with_trouble(plant_log("iso-dlc"), 400)
    live, live_vector = kf.live(), kf.live()
    reference = kf.initial_state()
    flags = 0
    for sample, interval in zip(samples, dt):
        estimate = live.update(sample, interval)
        by_vector = live_vector.update_inputs(sample.vector(), interval)
        reference, expected = kf.reference_step(reference, sample, interval)
        for one in (estimate, by_vector):
            np.testing.assert_array_equal(one.loads, expected.loads[0])
            np.testing.assert_array_equal(one.std, expected.std[0])
            np.testing.assert_array_equal(one.residual, expected.residual[0])
            assert one.flags == int(expected.flags[0])
        flags |= estimate.flags
    x, P, m = live.state
    np.testing.assert_array_equal(x, reference.x)
    np.testing.assert_array_equal(P, reference.P)
    np.testing.assert_array_equal(m, reference.m)
    assert flags & 0xFF00, "the guards acted on this log"


def test_live_filter_and_step_share_no_buffer(vehicle, plant_log):
    """Interleaving kf.step and a live filter on one TwoStageKF keeps both exact."""
    kf = TwoStageKF(vehicle)
    samples, dt = samples_with_trouble(plant_log("iso-dlc"), 130)
    live = kf.live()
    state = reference = kf.initial_state()
    for sample, interval in zip(samples, dt):
        state, _ = kf.step(state, sample, interval)
        estimate = live.update(sample, interval)
        reference, expected = kf.reference_step(reference, sample, interval)
        np.testing.assert_array_equal(state.x, expected.loads[0])
        np.testing.assert_array_equal(estimate.loads, expected.loads[0])
    initial = kf.initial_state()
    live.reset(initial.x, initial.P, initial.m)
    np.testing.assert_array_equal(live.state[0], initial.x)
    np.testing.assert_array_equal(live.state[1], initial.P)
