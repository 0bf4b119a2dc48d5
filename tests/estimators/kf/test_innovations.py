"""Innovation outputs of the two-stage KF, checked against an independent computation.

The suspension rows are updated first, on the predicted state: the innovation
of row FL is :math:`z_{FL} - x^-_{FL}` and its variance is
:math:`P^-_{FL,FL} + r_s / dt`, with :math:`x^- = x_{k-1}` and
:math:`P^- = P_{k-1} + q\\,dt\\,I`. Tolerance 1e-9 relative (same arithmetic,
other order).
"""

import numpy as np

from wheelload.estimators.kf.step_cache import UPDATE_ROWS
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.protocol import sample_intervals
from wheelload.models import gates_function, suspension_function
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log


def test_first_suspension_innovation_equals_independent_computation(fixed_vehicle):
    drive = synthetic_log(
        fixed_vehicle,
        slalom(duration=4.0),
        noise=SensorNoise(acceleration=0.05, travel=0.0003),
        spring_error=0.1,
        seed=5,
    )
    kf = TwoStageKF(fixed_vehicle)
    estimate, covariances = kf.run_with_covariance(drive)
    same, innovations = kf.run_innovations(drive)
    np.testing.assert_array_equal(same.loads, estimate.loads)
    # The pseudo-measurement with the vehicle's model terms where the log has
    # their inputs (the synthetic log has no rates or hub accelerometers).
    u = input_matrix(drive)
    gates = gates_function().map(len(drive))(np.isfinite(u).astype(float), kf.p)[0]
    z = np.array(suspension_function().map(len(drive))(np.nan_to_num(u), gates, kf.p)).T
    dt = sample_intervals(drive.t)
    q, r_s = kf.tuning[0], kf.tuning[1]
    # Row FL sees the prediction; later rows see the earlier rows' updates.
    y = z[1:, 0] - estimate.loads[:-1, 0]
    S = covariances[:-1, 0, 0] + q * dt[1:] + r_s / dt[1:]
    np.testing.assert_allclose(innovations.innovation[1:, 0], y, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(innovations.variance[1:, 0], S, rtol=1e-9)
    assert innovations.innovation.shape == (len(drive), len(UPDATE_ROWS))
    assert innovations.used.all()
    assert np.all(innovations.variance > 0)
    assert np.all(np.isfinite(innovations.innovation))
    frame = innovations.to_pandas()
    assert list(frame.columns[1:8]) == [f"innovation_{row}" for row in UPDATE_ROWS]
