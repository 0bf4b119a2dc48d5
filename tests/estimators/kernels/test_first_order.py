"""The differentiator's first-order filter equals scipy.signal's to the bit.

:mod:`wheelload.estimators.kernels.first_order` replaces ``scipy.signal`` (about 1 s
to import) in the velocity differentiator; the derived velocities, and so
every estimate of a log without ``v_*`` columns, must stay the same numbers:
equality, no tolerance.
"""

import numpy as np
import pytest
from scipy import signal

from wheelload.estimators.kernels import first_order

RATES = [50.0, 99.87, 100.0, 200.0, 333.3, 500.0, 1000.0, 1024.0, 2000.0, 10_000.0]


@pytest.mark.parametrize("fs", RATES)
@pytest.mark.parametrize("cutoff", [5.0, 20.0])
def test_bilinear_and_steady_state_equal_scipy(fs, cutoff):
    omega = 2.0 * np.pi * cutoff
    b, a = first_order.bilinear_differentiator(omega, fs)
    b_ref, a_ref = signal.bilinear([omega, 0.0], [1.0, omega], fs=fs)
    np.testing.assert_array_equal(b, b_ref)
    np.testing.assert_array_equal(a, a_ref)
    np.testing.assert_array_equal(first_order.lfilter_zi(b, a), signal.lfilter_zi(b_ref, a_ref))


@pytest.mark.parametrize("fs", [100.0, 1000.0])
def test_lfilter_equals_scipy_with_a_carried_state(fs):
    rng = np.random.default_rng(int(fs))
    t = np.arange(5000) / fs
    x = 0.02 * np.sin(2 * np.pi * 1.3 * t) + 1e-4 * rng.standard_normal(t.size)
    b, a = first_order.bilinear_differentiator(2 * np.pi * 20.0, fs)
    zi = signal.lfilter_zi(b, a) * x[0]
    y, zf = first_order.lfilter(b, a, x[:1234], zi)
    y2, zf2 = first_order.lfilter(b, a, x[1234:], zf)
    y_ref, zf_ref = signal.lfilter(b, a, x, zi=zi)
    np.testing.assert_array_equal(np.concatenate([y, y2]), y_ref)
    np.testing.assert_array_equal(zf2, zf_ref)


def test_lfilter_rejects_a_second_order_filter():
    with pytest.raises(ValueError, match="first-order"):
        first_order.lfilter(np.ones(3), np.array([1.0, 0.5, 0.1]), np.ones(5), np.zeros(2))
