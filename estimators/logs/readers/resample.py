"""Multi-rate channels onto one clock: linear interpolation or zero-order hold.

A log's channels arrive at their own rates (an IMU at 1 kHz, potentiometers
at 100 Hz, CAN signals at 50 Hz with dropouts). Each is resampled onto the
time stamps of one clock channel (the IMU's by default):

- :attr:`Method.LINEAR`: linear interpolation between the two source samples
  around a clock time;
- :attr:`Method.HOLD`: zero-order hold, the last source sample at or before a
  clock time (what a CAN receiver sees).

A clock time whose source samples are more than ``max_gap`` apart (linear),
or whose last source sample is older than ``max_gap`` (hold), or that lies
outside the source's time span, is a missing sample (NaN), never filled in.
Missing source values (NaN) are dropped first, so they count as gaps.
"""

from __future__ import annotations

import enum

import numpy as np

#: s, a source sample this close to a clock time is taken as at that time
#: (time stamps of different rates computed in floating point differ by ulps).
TIME_TOLERANCE = 1e-9


class Method(enum.Enum):
    """Resampling method of a channel."""

    LINEAR = "linear"
    HOLD = "hold"


def resample(
    t: np.ndarray, values: np.ndarray, clock: np.ndarray, method: Method, max_gap: float
) -> np.ndarray:
    """``values`` sampled at ``t`` resampled onto ``clock`` (see module docstring)."""
    t = np.asarray(t, float)
    values = np.asarray(values, float)
    keep = np.isfinite(t) & np.isfinite(values)
    t, values = t[keep], values[keep]
    out = np.full(clock.shape, np.nan)
    if t.size == 0:
        return out
    previous = np.searchsorted(t, clock + TIME_TOLERANCE, side="right") - 1
    started = previous >= 0
    previous = np.clip(previous, 0, t.size - 1)
    if method is Method.HOLD:
        fresh = started & (clock - t[previous] <= max_gap + TIME_TOLERANCE)
        out[fresh] = values[previous[fresh]]
        return out
    following = np.minimum(previous + 1, t.size - 1)
    at_sample = np.abs(clock - t[previous]) <= TIME_TOLERANCE
    inside = started & (clock <= t[-1] + TIME_TOLERANCE)
    bridged = t[following] - t[previous] <= max_gap + TIME_TOLERANCE
    ok = inside & (at_sample | bridged)
    out[ok] = np.interp(clock[ok], t, values)
    out[ok & at_sample] = values[previous[ok & at_sample]]
    return out
