"""MHE with robust losses, bias states and lagged output (estimators/mhe/window.py)."""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators.guards.settings import GUARDS_OFF
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.settings import (
    BiasStates,
    Constraint,
    Loss,
    MheSettings,
    ResidualLoss,
)
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

NOISE = SensorNoise(acceleration=0.05, travel=0.0003)
HUBER = ResidualLoss(kind=Loss.HUBER, threshold=2.0)


@pytest.fixture(scope="module")
def drive(fixed_vehicle):
    return synthetic_log(
        fixed_vehicle, slalom(duration=4.0), noise=NOISE, spring_error=0.08, seed=11
    )


def pooled_rmse(loads, reference):
    return float(np.sqrt(np.mean((loads - reference) ** 2)))


@pytest.mark.parametrize("constraint", list(Constraint))
def test_huber_with_a_far_corner_is_the_quadratic_window(fixed_vehicle, drive, constraint):
    """The auxiliary-variable QP with an unreachable corner equals the plain window."""
    signals = drive.slice(0, 150)
    far = ResidualLoss(kind=Loss.HUBER, threshold=1e4)
    plain = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=8, constraint=constraint))
    robust = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(horizon=8, constraint=constraint, suspension_loss=far)
    )
    # two QPs with different variables, each to 1e-6 kN: measured 0.33 N apart
    np.testing.assert_allclose(
        robust.run(signals).loads, plain.run(signals).loads, rtol=0, atol=2.0
    )


def test_robust_window_rejects_travel_spikes_the_kf_follows(fixed_vehicle, drive):
    d = drive.d.copy()
    rng = np.random.default_rng(3)
    spikes = rng.choice(np.arange(20, len(drive)), size=12, replace=False)
    d[spikes, rng.integers(0, 4, size=12)] += 0.03  # 30 mm single-sample spikes
    faulty = dataclasses.replace(drive, d=d)
    # the plain KF: without the guards (innovation gate, fault monitor) of
    # estimators/guards/settings.py
    kf = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF).run(faulty)
    settings = MheSettings(horizon=10, suspension_loss=HUBER, constraint_loss=HUBER)
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(faulty)
    clean = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF).run(drive)
    kf_error = pooled_rmse(kf.loads, drive.reference)
    mhe_error = pooled_rmse(mhe.loads, drive.reference)
    assert not mhe.fallback.any()
    assert kf_error > 1.3 * pooled_rmse(clean.loads, drive.reference)  # the spikes hurt the KF
    assert mhe_error < 0.75 * kf_error  # measured 30 % below the plain KF (147 vs 209 N)


def test_l1_loss_runs_and_stays_finite(fixed_vehicle, drive):
    settings = MheSettings(horizon=5, suspension_loss=ResidualLoss(kind=Loss.L1))
    mhe = MovingHorizonEstimator(fixed_vehicle, settings).run(drive.slice(0, 120))
    assert np.all(np.isfinite(mhe.loads)) and not mhe.fallback.any()
    assert pooled_rmse(mhe.loads, drive.reference[:120]) < 300.0


@pytest.fixture(scope="module")
def iso_dlc():
    """The bundled plant log (iso-dlc, sports car, every model term on)."""
    from wheelload.estimators import read_log
    from wheelload.studies.pipeline.example_log import example_log_path

    return read_log(example_log_path())


@pytest.fixture(scope="module")
def travel_bias_runs(fixed_vehicle, iso_dlc):
    """Travel-bias MHE on the clean plant log and with both front sensors 4 mm high."""
    from wheelload.studies.experiments.faults.sensor_faults import Fault, inject

    mhe = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(horizon=10, bias_states=BiasStates.TRAVEL)
    )
    return mhe.run(iso_dlc), mhe.run(inject(iso_dlc, Fault.TRAVEL_OFFSET))


def test_bias_states_take_up_a_4_mm_front_offset_on_a_plant_log(
    fixed_vehicle, iso_dlc, travel_bias_runs
):
    """The offset moves the travel-bias estimate by 4 mm and leaves the loads where they were.

    Reference for the offset: the same estimator on the clean log (the plant's
    ride height against the model's, see the xfail below). Measured: the change is
    [4.00, 4.01, 0.00, 0.00] mm from 0.02 s on, within 0.05 mm; loads 30.8 N against the
    plain KF's 65.0 N on the offset log.
    """
    from wheelload.studies.experiments.faults.sensor_faults import Fault, inject

    clean, offset = travel_bias_runs
    change = offset.bias[:, :4] - clean.bias[:, :4]
    first_second = slice(0, 100)  # under 5 s of driving: within the first second
    assert np.abs(change[first_second][-1] - [0.004, 0.004, 0.0, 0.0]).max() < 0.0005
    expected = np.tile([0.004, 0.004, 0.0, 0.0], (len(change) - 100, 1))
    np.testing.assert_allclose(change[100:], expected, rtol=0, atol=0.0005)
    kf = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF).run(
        inject(iso_dlc, Fault.TRAVEL_OFFSET)
    )
    offset_error = pooled_rmse(offset.loads, iso_dlc.reference)
    assert offset_error < 0.7 * pooled_rmse(kf.loads, iso_dlc.reference)  # 30 % below
    assert offset_error < 1.02 * pooled_rmse(clean.loads, iso_dlc.reference)


@pytest.mark.xfail(
    strict=True,
    reason="absolute offset within 0.5 mm: measured mean over the 5th second [3.71, 3.95, "
    "-0.65, -0.44] mm for [4, 4, 0, 0]. On the clean plant log the same states give [-0.29, "
    "-0.06, -0.65, -0.44] mm: the model's mismatch with the plant (mean suspension residual "
    "z - Fz of -46, +1, -20, -48 N; equilibrium residual 33 N, -60 N m, 18 N m), which the "
    "window cannot tell from a sensor offset",
)
def test_bias_states_recover_the_absolute_4_mm_offset_within_half_a_millimetre(travel_bias_runs):
    _, offset = travel_bias_runs
    fifth_second = offset.bias[400:500, :4].mean(axis=0)
    np.testing.assert_allclose(fifth_second, [0.004, 0.004, 0.0, 0.0], rtol=0, atol=0.0005)


def test_lagged_output_and_rts_beat_the_filter_on_a_plant_log(fixed_vehicle, iso_dlc):
    """50 ms lag (N = 10, lag 5) and the RTS smoother against the (guarded) KF on iso-dlc.

    Measured 23.27 N and 23.27 N against 23.48 N (-0.9 %: the filter trusts the bundled
    suspension noise more, so less is left to smooth); the lag-5 output of the soft window
    with the Kalman arrival is the fixed-lag smoother, equal to the RTS to 1e-3 N here.
    """
    kf = TwoStageKF(fixed_vehicle)
    filtered = pooled_rmse(kf.run(iso_dlc).loads, iso_dlc.reference)
    smoothed = pooled_rmse(kf.smooth(iso_dlc).loads, iso_dlc.reference)
    lagged = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=10, lag=5)).run(iso_dlc)
    lagged_error = pooled_rmse(lagged.loads, iso_dlc.reference)
    assert smoothed < 0.995 * filtered and lagged_error < 0.995 * filtered
    assert abs(lagged_error - smoothed) < 0.01 * smoothed


@pytest.mark.parametrize("constraint", list(Constraint))
def test_lagged_output_beats_the_filter_and_says_so(fixed_vehicle, drive, constraint):
    lagged = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(horizon=10, constraint=constraint, lag=5)
    ).run(drive)
    filtered = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=10, constraint=constraint))
    filtered = filtered.run(drive)
    assert lagged.lag == 5 and (lagged.to_pandas()["lag"] == 5).all()
    # a 50 ms fixed-lag smoother: measured 2.5 % (soft) and 5.3 % (hard) below the filter
    assert pooled_rmse(lagged.loads, drive.reference) < 0.985 * pooled_rmse(
        filtered.loads, drive.reference
    )


def test_settings_reject_bad_extensions():
    with pytest.raises(ValueError, match="lag"):
        MheSettings(horizon=5, lag=5)
    with pytest.raises(ValueError, match="soft"):
        MheSettings(constraint=Constraint.HARD, bias_states=BiasStates.ACCELERATION)
    with pytest.raises(ValueError, match="threshold"):
        ResidualLoss(kind=Loss.HUBER, threshold=0.0)
    with pytest.raises(TypeError, match="Loss"):
        ResidualLoss(kind="huber")
    with pytest.raises(ValueError, match="exclude"):
        MheSettings(bias_states=BiasStates.TRAVEL | BiasStates.RIDE_HEIGHT)
    with pytest.raises(ValueError, match="exclude"):
        MheSettings(bias_states=BiasStates.ACCELERATION | BiasStates.LATERAL)
    with pytest.raises(ValueError, match="soft"):
        MheSettings(constraint=Constraint.HARD, bias_states=BiasStates.LATERAL)


def test_ride_height_offsets_are_orthogonal_to_the_warp(fixed_vehicle):
    """Per-axle offsets move no load along the equilibrium's null vector (observable)."""
    mhe = MovingHorizonEstimator(
        fixed_vehicle, MheSettings(bias_states=BiasStates.RIDE_HEIGHT | BiasStates.LATERAL)
    )
    from wheelload.models import INPUTS

    T = mhe.travel_basis
    assert T.shape == (4, 2) and mhe.window_qp.travel_basis is T  # the basis the window uses

    u0 = np.zeros(len(INPUTS))
    J = np.asarray(mhe.residuals(u0, np.ones(len(INPUTS)), 0.01, mhe.p, mhe.tuning)[1])
    # relative to the load shift of a unit offset (~75 kN/m): rounding only
    assert np.abs(mhe.null @ J @ T).max() < 1e-9 * np.abs(J @ T).max()
    assert mhe.acceleration_columns == [1]  # ay only


def test_huber_window_on_a_plant_log_with_a_stuck_travel_sensor(fixed_vehicle, iso_dlc):
    """Bundled plant log (iso-dlc); front-left travel stuck from 20 % of the log.

    Huber at 0.5σ on the suspension rows: the model's own residuals on this plant are
    0.1-0.2σ (25-50 N against σ = 250 N per sample), so a 0.2σ corner also discounts
    the clean rows (measured 29.8 N, +9 %) while 0.5σ leaves them quadratic.
    """
    from wheelload.studies.experiments.faults.sensor_faults import Fault, inject

    huber = ResidualLoss(kind=Loss.HUBER, threshold=0.5)
    mhe = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=10, suspension_loss=huber))
    # against the plain KF; the guarded KF (fault monitor) isolates the stuck sensor itself
    kf = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF)
    stuck = inject(iso_dlc, Fault.STUCK)
    robust_error = pooled_rmse(mhe.run(stuck).loads, iso_dlc.reference)
    kf_error = pooled_rmse(kf.run(stuck).loads, iso_dlc.reference)
    assert robust_error < 0.7 * kf_error  # measured 76.9 N against 132.1 N (-42 %)
    clean_error = pooled_rmse(mhe.run(iso_dlc).loads, iso_dlc.reference)
    # on the clean log it costs nothing: measured 27.3 N against the KF's 27.4 N (guarded
    # or not: no guard acts on the clean log)
    guarded = pooled_rmse(TwoStageKF(fixed_vehicle).run(iso_dlc).loads, iso_dlc.reference)
    assert clean_error < 1.05 * guarded


def test_step_equals_run_for_the_extended_window(fixed_vehicle, drive):
    from wheelload.estimators import Sample
    from wheelload.estimators.protocol import sample_intervals

    signals = drive.slice(0, 40)
    settings = MheSettings(
        horizon=6, suspension_loss=HUBER, constraint_loss=HUBER, bias_states=BiasStates.TRAVEL
    )
    mhe = MovingHorizonEstimator(fixed_vehicle, settings)
    whole = mhe.run(signals)
    dt = sample_intervals(signals.t)
    state = mhe.initial_state(float(np.median(dt)))
    for k in range(len(signals)):
        sample = Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=float(signals.vx[k]))
        state, one = mhe.step(state, sample, float(dt[k]))
        # filter compiled in run, CasADi in step: rounding, within the solver tolerance
        np.testing.assert_allclose(one.loads[0], whole.loads[k], rtol=0, atol=1e-2)
        np.testing.assert_allclose(one.bias[0], whole.bias[k], rtol=0, atol=1e-6)


def test_ride_heights_and_ay_bias_take_up_both_slow_faults_on_a_plant_log(fixed_vehicle, iso_dlc):
    """Front ride height 4 mm off, or ay biased by 0.5 m/s^2 from 20 % of the log (iso-dlc).

    Three slow unknowns against three equilibrium rows, so they are told apart (travel
    offsets with ax/ay biases are not: the 4 mm offset was read as ax = +0.94 m/s^2).
    Measured 27.0 N against the plain KF's 108.4 N (offset) and 32.2 N against 40.0 N (ay).
    """
    from wheelload.studies.experiments.faults.sensor_faults import Fault, inject

    settings = MheSettings(
        horizon=10,
        suspension_loss=ResidualLoss(kind=Loss.HUBER, threshold=0.2),
        bias_states=BiasStates.RIDE_HEIGHT | BiasStates.LATERAL,
    )
    mhe = MovingHorizonEstimator(fixed_vehicle, settings)
    kf = TwoStageKF(fixed_vehicle, guard_settings=GUARDS_OFF)
    for fault in (Fault.TRAVEL_OFFSET, Fault.ACCELERATION_BIAS):
        faulty = inject(iso_dlc, fault)
        estimate = mhe.run(faulty)
        error = pooled_rmse(estimate.loads, iso_dlc.reference)
        assert error < 0.85 * pooled_rmse(kf.run(faulty).loads, iso_dlc.reference), fault
    # the ay bias read at the end of the log (true 0.5 m/s^2; measured 0.39)
    assert 0.25 < estimate.bias[-1, 4] < 0.6


@pytest.mark.parametrize(
    "settings",
    [
        MheSettings(horizon=6, suspension_loss=ResidualLoss(kind=Loss.L1),
                    constraint_loss=HUBER, bias_states=BiasStates.TRAVEL | BiasStates.ACCELERATION),
        MheSettings(horizon=5, constraint=Constraint.HARD, bounded=True, max_load=2e4,
                    suspension_loss=HUBER, bias_states=BiasStates.TRAVEL),
        MheSettings(horizon=4, bias_states=BiasStates.RIDE_HEIGHT | BiasStates.LATERAL),
    ],
    ids=["soft-l1-huber-5-bias", "hard-bounded-huber-travel", "soft-ride-height-ay"],
)  # fmt: skip
def test_sparse_window_values_equal_the_dense_assembly(fixed_vehicle, drive, settings):
    """Each sample's Px and q at the fixed pattern against the dense assembly of the same window.

    The same terms summed in the same order at each entry; only the links' products
    are batched: equal to 1e-12 of the largest entry. The dense matrix has nothing
    outside the pattern (no entry the values could drop).
    """
    mhe = MovingHorizonEstimator(fixed_vehicle, settings)
    qp = mhe.window_qp
    sparse = qp.assemble_values
    outside = np.ones((qp.n, qp.n), dtype=bool)
    outside[qp.rows, qp.cols] = False
    outside[np.tril_indices(qp.n, -1)] = False  # the lower triangle is not loaded
    checked = []

    def both(window, j0, *args):
        Px, q = sparse(window, j0, *args)
        H, g = qp.assemble(window, j0, *args)
        np.testing.assert_allclose(Px, H[qp.rows, qp.cols][qp.order], rtol=0,
                                   atol=1e-12 * np.abs(Px).max())  # fmt: skip
        np.testing.assert_allclose(q, g, rtol=0, atol=1e-12 * np.abs(g).max())
        assert not H[outside].any()
        checked.append(j0)
        return Px, q

    qp.assemble_values = both
    mhe.run(drive.slice(0, 40))
    assert set(checked) == set(range(settings.horizon))  # the start-up windows too
