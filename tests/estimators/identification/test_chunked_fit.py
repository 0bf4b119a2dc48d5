"""The chunked fit (regressors a chunk at a time, R factors kept) equals the dense fit.

On the bundled plant log (a simulated drive with reference loads), cut into
chunks of 300 samples (4.5 chunks, the last one short): fitted values and
standard errors agree to 1e-9 relative for least squares and two-stage
least squares (both solve the same problem by different linear algebra, QR
of the whole matrix or of the stacked factors, so they differ by rounding
times the conditioning; measured 1e-15 to 1e-12), and for the robust losses
(Newton steps to the minimiser from scipy's trust-region solution on the
whole matrix or from the least-squares solution over the chunks).

Each case fits twice over many small chunks: 11-23 s per case at a load
average of about 8 on 2 cores (fewer samples would leave parameters
unidentified and the comparison thinner).
"""

import numpy as np
import pytest

from wheelload.estimators.identification import default_model, drive_gates, identify, read_drive
from wheelload.estimators.identification.fit import FitLoss, FitPath, FitSettings
from wheelload.models import ModelParameters
from wheelload.models.runtime.spill import on_disk
from wheelload.studies.pipeline.example_log import example_log_path


@pytest.fixture(scope="module")
def drive(vehicle):
    p = ModelParameters.from_vehicle(vehicle)
    model = default_model()
    data = (read_drive(example_log_path(), model.channel_names(), model.optional),)
    return default_model(drive_gates(p, data)), data, p


@pytest.mark.parametrize(
    ("loss", "instrumental", "tolerance"),
    [
        (FitLoss.LINEAR, False, 1e-9),
        (FitLoss.LINEAR, True, 1e-9),
        (FitLoss.SOFT_L1, False, 1e-9),
        (FitLoss.HUBER, False, 1e-9),
    ],
)
def test_chunked_fit_equals_the_dense_fit(drive, loss, instrumental, tolerance):
    model, data, p = drive
    fits = {
        path: identify(
            model, data, p, FitSettings(path=path, loss=loss, instrumental=instrumental, chunk=300)
        )
        for path in FitPath
    }
    dense, chunked = fits[FitPath.DENSE], fits[FitPath.CHUNKED]
    assert len(dense.free) >= 10
    assert chunked.free == dense.free
    assert chunked.warnings == dense.warnings
    free = list(dense.free)
    np.testing.assert_allclose(chunked.value[free], dense.value[free], rtol=tolerance, atol=0)
    np.testing.assert_allclose(
        chunked.std_error[free], dense.std_error[free], rtol=tolerance, atol=0
    )
    np.testing.assert_allclose(chunked.scale, dense.scale, rtol=tolerance, atol=0)
    assert chunked.rmse().keys() == dense.rmse().keys()
    for key, value in dense.rmse().items():
        assert chunked.rmse()[key] == pytest.approx(value, rel=tolerance)
    # The chunked result keeps a time-spread sample of the rows for the figures.
    assert 0 < chunked.rows.y.size <= dense.rows.y.size


def test_chunk_size_must_be_positive(drive):
    model, data, p = drive
    with pytest.raises(ValueError, match="chunk: give a positive number"):
        identify(model, data, p, FitSettings(chunk=0))


def test_a_fit_kept_on_disk_equals_the_dense_fit(drive):
    """The path of a long log: the data set and the per-row residuals on temporary files
    (``spill_bytes=0``), read a chunk at a time with their pages dropped after each, the
    robust loss's inlier rows taken from the residual file; the dense fit in memory."""
    model, data, p = drive
    spilled = (
        read_drive(example_log_path(), model.channel_names(), model.optional, spill_bytes=0),
    )
    assert on_disk(spilled[0].target)
    settings = {"loss": FitLoss.HUBER, "chunk": 300}
    dense = identify(model, data, p, FitSettings(path=FitPath.DENSE, **settings))
    chunked = identify(model, spilled, p, FitSettings(spill_bytes=0, **settings))
    free = list(dense.free)
    assert chunked.free == dense.free and len(free) >= 10
    np.testing.assert_allclose(chunked.value[free], dense.value[free], rtol=1e-9, atol=0)
    np.testing.assert_allclose(chunked.std_error[free], dense.std_error[free], rtol=1e-9, atol=0)
    np.testing.assert_allclose(chunked.scale, dense.scale, rtol=1e-9, atol=0)
    np.testing.assert_allclose(chunked.autocorrelation, dense.autocorrelation, rtol=1e-9)
