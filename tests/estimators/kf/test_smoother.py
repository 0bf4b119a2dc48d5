"""RTS smoother over the two-stage KF: equals an independent numpy RTS, beats the filter."""

import numpy as np
import pandas as pd

from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.protocol import sample_intervals
from wheelload.studies.cli import main
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log


def numpy_rts(x, P, dt, q):
    """Textbook RTS for the random walk Q = q dt I (Särkkä 2013, Thm 8.2)."""
    xs, Ps = x.copy(), P.copy()
    for k in range(len(x) - 2, -1, -1):
        P_pred = P[k] + q * dt[k + 1] * np.eye(4)
        C = P[k] @ np.linalg.inv(P_pred)
        xs[k] = x[k] + C @ (xs[k + 1] - x[k])
        Ps[k] = P[k] + C @ (Ps[k + 1] - P_pred) @ C.T
    return xs, Ps


def test_compiled_smoother_equals_numpy_rts_and_beats_the_filter(fixed_vehicle):
    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    signals = synthetic_log(
        fixed_vehicle, slalom(duration=10.0), noise=noise, spring_error=0.08, seed=4
    )
    signals.t[500:] += 0.02  # one longer interval: the smoother takes each sample's own dt
    kf = TwoStageKF(fixed_vehicle)
    filtered, P = kf.run_with_covariance(signals)
    smoothed = kf.smooth(signals)
    xs, Ps = numpy_rts(filtered.loads, P, sample_intervals(signals.t), kf.tuning[0])
    # both in double precision on 4 kN loads; rounding only (measured 1e-12 N)
    np.testing.assert_allclose(smoothed.loads, xs, rtol=0, atol=1e-6)
    np.testing.assert_allclose(smoothed.std, np.sqrt(np.einsum("kii->ki", Ps)), rtol=1e-9)
    own = np.sqrt(np.einsum("kii->ki", P))  # the filter's own sigma
    assert np.all(smoothed.std <= own + 1e-9)  # smoothing never loses information
    np.testing.assert_array_equal(smoothed.flags, filtered.flags)

    def rmse(loads):
        return np.sqrt(np.mean((loads - signals.reference) ** 2))

    # measured 2.1 % lower (121.9 vs 124.5 N; 6 % with the former suspension noise 625 N^2 s)
    assert rmse(smoothed.loads) < 0.99 * rmse(filtered.loads)


def test_estimate_smooth_writes_the_smoothed_loads(tmp_path, capsys):
    out = tmp_path / "smoothed.csv"
    assert main(["estimate", "--example", "--smooth", "--out", str(out)]) == 0
    frame = pd.read_csv(out)
    assert np.isfinite(frame[["fz_fl", "fz_fr", "fz_rl", "fz_rr"]].to_numpy()).all()
    filtered = tmp_path / "filtered.csv"
    assert main(["estimate", "--example", "--out", str(filtered)]) == 0
    assert not np.allclose(frame["fz_fl"], pd.read_csv(filtered)["fz_fl"])


def test_mhe_lagged_output_is_the_rts_smoother(fixed_vehicle):
    """Linear-Gaussian window with the Kalman arrival: its lag-L output is the fixed-lag
    smoother, equal to RTS once the smoother gain has decayed within L samples."""
    from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
    from wheelload.estimators.mhe.settings import MheSettings, SolverSettings

    noise = SensorNoise(acceleration=0.05, travel=0.0003)
    signals = synthetic_log(
        fixed_vehicle, slalom(duration=3.0), noise=noise, spring_error=0.08, seed=9
    )
    tight = SolverSettings(eps_abs=1e-9, eps_rel=1e-9, max_iter=20000)
    lagged = MovingHorizonEstimator(fixed_vehicle, MheSettings(horizon=8, lag=6, solver=tight))
    lagged = lagged.run(signals)
    smoothed = TwoStageKF(fixed_vehicle).smooth(signals)
    # gain decay over 6 samples and solver tolerance: measured 9e-4 N on the plant log (lag 5)
    np.testing.assert_allclose(lagged.loads[:-6], smoothed.loads[:-6], rtol=0, atol=0.01)
