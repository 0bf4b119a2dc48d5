r"""A steady-state kinematic Kalman filter: a rate and its derivative from noisy samples.

State :math:`x = [w, \dot w]`, white-noise-jerk model (Bar-Shalom, Li & Kirubarajan,
*Estimation with Applications to Tracking and Navigation*, 2001, §6.2.2, the
"white noise acceleration" model of the rate :math:`w`), measurement :math:`z = w + v`:

.. math::

    F = \begin{bmatrix} 1 & T \\ 0 & 1 \end{bmatrix},\quad
    Q = q \begin{bmatrix} T^3/3 & T^2/2 \\ T^2/2 & T \end{bmatrix},\quad
    H = [1\;\; 0],\quad R = r

with :math:`q` the jerk's spectral density [(rad/s^3)^2/Hz] and :math:`r` the rate's
noise variance per sample. The gain is the steady state of the Riccati recursion
(:func:`steady_gain`), so the filter is linear and time invariant: per sample

.. math::

    x^- = F x,\quad x = x^- + K (z - x^-_0)

(an alpha-beta filter, :math:`\alpha = K_0,\ \beta = K_1 T`). Its bandwidth follows
:math:`q/r`: it widens with the sample rate at a given noise density and narrows with
the noise. :func:`kinematic_filter` runs it over a signal in C (compiled once and
cached like the travel differentiator, :mod:`~wheelload.estimators.kernels.first_order`).
"""

from __future__ import annotations

import ctypes
import functools

import numpy as np

from wheelload.estimators.kernels.c_function import c_function

SOURCE = """
/* alpha-beta filter: x- = F x; x = x- + K (z - x-_0); y = x_1 (the derivative). */
void wheelload_kinematic(long n, double T, const double *K, const double *z,
                         double *y, double *x)
{
    double w = x[0], w_dot = x[1];
    long k;
    for (k = 0; k < n; ++k) {
        const double predicted = w + T * w_dot;
        const double residual = z[k] - predicted;
        w = predicted + K[0] * residual;
        w_dot = w_dot + K[1] * residual;
        y[k] = w_dot;
    }
    x[0] = w;
    x[1] = w_dot;
}
"""


def steady_gain(T: float, q: float, r: float) -> np.ndarray:
    """The steady-state Kalman gain ``K`` (2,) of the module's model (Riccati iterated, once
    per ``T, q, r``: a tuning search asks for the same gains thousands of times)."""
    if not (T > 0.0 and q > 0.0 and r > 0.0):
        raise ValueError(f"sample interval {T}, jerk density {q}, noise {r} must be positive")
    return np.array(_steady_gain(float(T), float(q), float(r)))


@functools.lru_cache(maxsize=256)
def _steady_gain(T: float, q: float, r: float) -> tuple[float, float]:
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q = q * np.array([[T**3 / 3.0, T**2 / 2.0], [T**2 / 2.0, T]])
    P = Q.copy()
    K = np.zeros(2)
    for _ in range(100000):
        predicted = F @ P @ F.T + Q
        gain = predicted[:, 0] / (predicted[0, 0] + r)
        P = predicted - np.outer(gain, predicted[0])
        if np.allclose(gain, K, rtol=1e-13, atol=0.0):
            return tuple(gain)
        K = gain
    return tuple(K)


@functools.cache
def _kernel():
    argtypes = [ctypes.c_long, ctypes.c_double] + [ctypes.c_void_p] * 4
    return c_function(SOURCE, "wheelload_kinematic", "estimate body-rate derivatives", argtypes)


def kinematic_filter(
    T: float, K: np.ndarray, z: np.ndarray, x: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The derivative estimates of the samples ``z`` from the state ``x`` = [w, w_dot]:
    ``(w_dot, x at the end)``."""
    z = np.ascontiguousarray(z, dtype=float)
    if z.ndim != 1:
        raise ValueError("a 1-D signal is expected")
    K = np.ascontiguousarray(K, dtype=float)
    y = np.empty_like(z)
    state = np.array(x, dtype=float).reshape(2)
    _kernel()(z.size, float(T), K.ctypes.data, z.ctypes.data, y.ctypes.data, state.ctypes.data)
    return y, state
