"""The numpy zero-phase low-pass and running median equal scipy.signal's.

The wiring checks use :mod:`wheelload.estimators.kernels.zero_phase` instead of
``scipy.signal`` (whose import is most of a warm ``wheelload estimate``).
Tolerance: 1e-10 of the signal's scale for the filters: the FFT convolution
with a closed-form impulse response rounds differently from scipy's
recursion; at a cutoff of 0.002 of Nyquist (1 Hz at 1 kHz) the response has
~10^4 taps and the two differ by up to ~2e-12 of the scale. The median
exactly (a selection, no arithmetic).
"""

import numpy as np
import pytest
from scipy import signal

from wheelload.estimators.kernels import zero_phase


@pytest.mark.parametrize("cutoff", [0.002, 0.02, 0.2, 0.9])
def test_butter2_equals_scipy(cutoff):
    b, a = zero_phase.butter2(cutoff)
    b_ref, a_ref = signal.butter(2, cutoff)
    np.testing.assert_allclose(b, b_ref, rtol=1e-12, atol=0)
    np.testing.assert_allclose(a, a_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(zero_phase.lfilter_zi(b, a), signal.lfilter_zi(b, a), rtol=1e-12)


def _log_like(n, rng):
    t = np.arange(n) * 0.01
    x = 3.0 * np.sin(0.7 * t) + 0.4 * np.sin(9.0 * t) + 0.05 * rng.standard_normal(n)
    x[n // 3] += 40.0  # a spike
    return x + 9.81


@pytest.mark.parametrize("cutoff", [0.002, 0.02, 0.2, 0.9])
@pytest.mark.parametrize("n", [10, 31, 1000, 12_000])
def test_filtfilt_and_lfilter_equal_scipy(cutoff, n):
    rng = np.random.default_rng(n)
    x = _log_like(n, rng)
    b, a = zero_phase.butter2(cutoff)
    scale = np.max(np.abs(x))
    zi = signal.lfilter_zi(b, a) * x[0]
    np.testing.assert_allclose(
        zero_phase.lfilter(b, a, x, zi),
        signal.lfilter(b, a, x, zi=zi)[0],
        rtol=0,
        atol=1e-10 * scale,
    )
    np.testing.assert_allclose(
        zero_phase.filtfilt(b, a, x), signal.filtfilt(b, a, x), rtol=0, atol=1e-10 * scale
    )


def test_filtfilt_rejects_a_signal_shorter_than_its_padding():
    b, a = zero_phase.butter2(0.1)
    with pytest.raises(ValueError, match="more than 9 samples"):
        zero_phase.filtfilt(b, a, np.ones(9))


@pytest.mark.parametrize("window", [1, 3, 5])
def test_medfilt_equals_scipy_exactly(window):
    x = _log_like(997, np.random.default_rng(3))
    np.testing.assert_array_equal(zero_phase.medfilt(x, window), signal.medfilt(x, window))
