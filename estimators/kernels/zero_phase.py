r"""Zero-phase second-order Butterworth low-pass and running median in numpy.

What the wiring checks (:mod:`wheelload.estimators.logs.checks`) need of
``scipy.signal`` (``butter(2, Wn)``, ``filtfilt``, ``medfilt``), without its
import (about 1 s, most of a warm ``wheelload estimate``):

- :func:`butter2` is the bilinear transform of the analogue Butterworth
  prototype :math:`1/(s^2 + \sqrt2 s + 1)` with the cutoff pre-warped,
  :math:`K = \tan(\pi W_n / 2)`: :math:`b = K^2 (1, 2, 1)/n`,
  :math:`a = (1, 2(K^2 - 1)/n, (1 - \sqrt2 K + K^2)/n)`, :math:`n = 1 + \sqrt2 K + K^2`;
- :func:`lfilter` runs the IIR filter (transposed direct form II state ``zi``,
  as ``scipy.signal.lfilter``) as the FFT convolution of the input with the
  impulse response, cut where it has decayed below the double precision of
  its peak, plus the free response of the initial state;
- :func:`filtfilt` is ``scipy.signal.filtfilt``'s default (odd extension by
  ``3 max(len(a), len(b))`` samples, steady-state initial conditions of
  :func:`lfilter_zi`, forward then backward);
- :func:`medfilt` is ``scipy.signal.medfilt`` (zero padding at the ends).

The test suite checks each against ``scipy.signal`` (to 1e-10 of the signal
scale; the median exactly).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from wheelload.estimators.kernels import order_statistics

#: Relative size at which an impulse response is cut (below double precision of its peak).
_DECAYED = 1e-18


def butter2(cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of the second-order Butterworth low-pass; ``cutoff`` relative to Nyquist."""
    if not 0.0 < cutoff < 1.0:
        raise ValueError(f"cutoff must be in (0, 1) of the Nyquist frequency, got {cutoff}")
    K = math.tan(0.5 * math.pi * cutoff)
    norm = 1.0 + math.sqrt(2.0) * K + K * K
    b0 = K * K / norm
    b = np.array([b0, 2.0 * b0, b0])
    a = np.array([1.0, 2.0 * (K * K - 1.0) / norm, (1.0 - math.sqrt(2.0) * K + K * K) / norm])
    return b, a


def lfilter_zi(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Steady-state initial state of :func:`lfilter` for a unit step (second order)."""
    b, a = _second_order(b, a)
    # zi = (I - A)^-1 B with the companion matrix of the transposed direct form II.
    companion = np.array([[-a[1], 1.0], [-a[2], 0.0]])
    B = b[1:] - a[1:] * b[0]
    return np.linalg.solve(np.eye(2) - companion, B)


def _second_order(b: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    b, a = np.asarray(b, float), np.asarray(a, float)
    if b.shape != (3,) or a.shape != (3,) or a[0] != 1.0:
        raise ValueError("a second-order filter with a[0] = 1 is expected")
    return b, a


def _recursion_response(a: np.ndarray, length: int) -> np.ndarray:
    r"""Impulse response of :math:`1/A(z)`, ``length`` samples.

    With complex poles :math:`r e^{\pm i\theta}`: :math:`h_n = r^n \sin((n+1)\theta)/\sin\theta`;
    otherwise the recursion :math:`h_n = -a_1 h_{n-1} - a_2 h_{n-2}`.
    """
    a1, a2 = float(a[1]), float(a[2])
    n = np.arange(length)
    if a1 * a1 < 4.0 * a2:
        r = math.sqrt(a2)
        theta = math.acos(-a1 / (2.0 * r))
        return r**n * np.sin((n + 1) * theta) / math.sin(theta)
    h = np.zeros(length)
    previous, current = 0.0, 1.0
    for k in range(length):
        h[k] = current
        previous, current = current, -a1 * current - a2 * previous
    return h


def _response_length(a: np.ndarray, n: int) -> int:
    """Samples after which the impulse response of 1/A has decayed below :data:`_DECAYED`."""
    radius = float(np.max(np.abs(np.roots(a))))
    if not radius < 1.0:
        raise ValueError("the filter is not stable")
    decay = math.log(_DECAYED) / math.log(radius) if radius > 0.0 else 1.0
    return int(min(n, math.ceil(decay) + 8))


@functools.lru_cache(maxsize=16)
def _responses(b: tuple[float, ...], a: tuple[float, ...], n: int):
    """For :func:`lfilter` of ``n`` samples: the response length, the impulse response of
    1/A, the FFT size and the spectrum of the impulse response of B/A (read-only; kept, as
    the checks filter every channel of a window with one filter)."""
    a_array = np.array(a)
    length = _response_length(a_array, n)
    recursion = _recursion_response(a_array, length)
    impulse = np.convolve(np.array(b), recursion)[:length]
    size = 1 << (n + length - 1).bit_length()
    spectrum = np.fft.rfft(impulse, size)
    recursion.flags.writeable = False
    spectrum.flags.writeable = False
    return length, recursion, size, spectrum


def lfilter(b: np.ndarray, a: np.ndarray, x: np.ndarray, zi: np.ndarray) -> np.ndarray:
    """``scipy.signal.lfilter(b, a, x, zi=zi)[0]`` of a second-order filter, 1-D ``x``."""
    b, a = _second_order(b, a)
    x = np.asarray(x, float)
    n = x.size
    if n == 0:
        return x.copy()
    length, recursion, size, spectrum = _responses(tuple(b), tuple(a), n)
    forced = np.fft.irfft(np.fft.rfft(x, size) * spectrum, size)[:n]
    free = np.zeros(n)
    free[:length] += zi[0] * recursion
    free[1 : length + 1] += zi[1] * recursion[: min(length, n - 1)]
    return forced + free


def filtfilt(b: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Zero-phase forward-backward filter: ``scipy.signal.filtfilt(b, a, x)`` (odd padding)."""
    x = np.asarray(x, float)
    pad = 3 * max(len(a), len(b))
    if x.size <= pad:
        raise ValueError(f"the signal needs more than {pad} samples, got {x.size}")
    extended = np.concatenate([2.0 * x[0] - x[pad:0:-1], x, 2.0 * x[-1] - x[-2 : -pad - 2 : -1]])
    zi = lfilter_zi(b, a)
    forward = lfilter(b, a, extended, zi * extended[0])
    backward = lfilter(b, a, forward[::-1], zi * forward[-1])[::-1]
    return backward[pad:-pad]


def medfilt(x: np.ndarray, window: int) -> np.ndarray:
    """Running median over an odd ``window``, zero-padded at the ends (``signal.medfilt``)."""
    if window < 1 or window % 2 == 0:
        raise ValueError(f"the median window must be odd and positive, got {window}")
    x = np.asarray(x, float)
    half = window // 2
    padded = np.concatenate([np.zeros(half), x, np.zeros(half)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, window)
    return order_statistics.median(windows, axis=-1)
