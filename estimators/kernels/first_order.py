r"""The velocity differentiator's first-order filter without ``scipy.signal``.

:class:`~wheelload.estimators.logs.signals.Differentiator` filters each travel
(or body rate) with :math:`H(s) = \omega s / (s + \omega)` discretised by the
bilinear transform. ``scipy.signal`` gives ``bilinear``, ``lfilter_zi`` and
``lfilter`` for it but takes about 1 s to import, most of a warm
``wheelload estimate``. This module computes the same numbers to the bit:

- :func:`bilinear_differentiator`: ``scipy.signal.bilinear([w, 0], [1, w], fs)``
  by its own algorithm (numpy polynomials in :math:`(z \pm 1)` scaled by
  :math:`\sqrt{2 f_s}`, then divided by the leading denominator coefficient);
- :func:`lfilter_zi`: the steady state of a unit step, ``np.linalg.solve`` of
  :math:`(I - C^T) z = b_{1:} - a_{1:} b_0` (:math:`C` the companion matrix),
  as ``scipy.signal.lfilter_zi``;
- :func:`lfilter`: the transposed direct form II recursion
  :math:`y_k = z + b_0 x_k,\; z \leftarrow x_k b_1 - y_k a_1` in C, the
  operations and order of scipy's ``lfilter`` kernel; compiled once and cached
  like the filter's loop (:func:`wheelload.models.runtime.build_folder.cached_library`).

The test suite checks all three against ``scipy.signal`` for equality.
"""

from __future__ import annotations

import ctypes
import functools

import numpy as np

from wheelload.estimators.kernels.c_function import c_function

SOURCE = """
/* y_k = z + b0 x_k; z = x_k b1 - y_k a1 (transposed direct form II, first order). */
void wheelload_first_order(long n, const double *b, const double *a, const double *x,
                           double *y, double *z)
{
    double state = z[0];
    long k;
    for (k = 0; k < n; ++k) {
        const double out = state + b[0] * x[k];
        state = x[k] * b[1] - out * a[1];
        y[k] = out;
    }
    z[0] = state;
}
"""


def bilinear_differentiator(omega: float, fs: float) -> tuple[np.ndarray, np.ndarray]:
    r"""``(b, a)`` of :math:`\omega s/(s + \omega)` by the bilinear transform at ``fs`` [Hz]."""
    if not (omega > 0.0 and fs > 0.0):
        raise ValueError(f"corner {omega} rad/s and sample rate {fs} Hz must be positive")
    polynomial = np.polynomial.Polynomial
    fac = np.sqrt(fs * 2)
    zp1 = polynomial((+1, 1)) / fac  # (z + 1) / fac
    zm1 = polynomial((-1, 1)) * fac  # (z - 1) * fac
    b, a = np.array([omega, 0.0]), np.array([1.0, omega])
    numerator = sum(b_ * zp1 ** (1 - q) * zm1**q for q, b_ in enumerate(b[::-1]))
    denominator = sum(a_ * zp1 ** (1 - p) * zm1**p for p, a_ in enumerate(a[::-1]))
    num, den = numerator.coef[::-1].copy(), denominator.coef[::-1].copy()
    return num / den[0], den / den[0]


def lfilter_zi(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Initial state of :func:`lfilter` for a unit step in steady state (first order)."""
    b, a = _first_order(b, a)
    companion = np.array([[-a[1] / a[0]]])
    return np.linalg.solve(np.eye(1) - companion.T, b[1:] - a[1:] * b[0])


def _first_order(b, a) -> tuple[np.ndarray, np.ndarray]:
    b, a = np.asarray(b, float), np.asarray(a, float)
    if b.shape != (2,) or a.shape != (2,) or a[0] != 1.0:
        raise ValueError("a first-order filter with a[0] = 1 is expected")
    return b, a


@functools.cache
def _kernel():
    argtypes = [ctypes.c_long] + [ctypes.c_void_p] * 5
    return c_function(SOURCE, "wheelload_first_order", "derive suspension velocities", argtypes)


def lfilter(
    b: np.ndarray, a: np.ndarray, x: np.ndarray, zi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.signal.lfilter(b, a, x, zi=zi)`` of a first-order filter: ``(y, zf)``."""
    b, a = _first_order(b, a)
    x = np.ascontiguousarray(x, dtype=float)
    if x.ndim != 1:
        raise ValueError("a 1-D signal is expected")
    y = np.empty_like(x)
    z = np.array(zi, dtype=float).reshape(1)
    _kernel()(x.size, b.ctypes.data, a.ctypes.data, x.ctypes.data, y.ctypes.data, z.ctypes.data)
    return y, z
