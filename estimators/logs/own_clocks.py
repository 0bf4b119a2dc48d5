"""A log of channels on their own clocks (``[clock] union``): each column NaN where it has no
new value, so a per-channel filter or check works on the channel's own samples.

:func:`on_own_stamps` runs a causal filter (the travel differentiator, the body-rate
derivative estimator) over each channel's own finite samples, at its own sample interval,
restarted after a gap in its own stamps; :func:`on_clock` puts channels onto one clock (the
IMU's own stamps, :func:`on_imu_clock`) for the checks that compare channels sample by
sample (wiring, lags, plausibility).

Example
-------
>>> v = on_own_stamps(lambda steps, name: Differentiator(steps, 1), t, d, TRAVEL)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from wheelload.estimators.logs.readers.resample import Method, resample
from wheelload.estimators.types import Steps


def on_own_stamps(
    make_filter: Callable, t: np.ndarray, columns: np.ndarray, names: Sequence[str]
) -> np.ndarray:
    """Each column of ``columns`` (n, k) through a causal filter on its own finite samples.

    ``make_filter(steps, name)`` builds a one-channel filter (a
    :class:`~wheelload.estimators.logs.signals.ChunkFilter`) from the channel's own sample
    intervals (:class:`~wheelload.estimators.types.Steps` of its stamps: their median sets
    the filter's step, their gaps restart it); its outputs go to the channel's rows, NaN
    elsewhere and for a channel with fewer than two samples.
    """
    out = np.full(columns.shape, np.nan)
    for k, name in enumerate(names):
        rows = np.flatnonzero(np.isfinite(columns[:, k]))
        if rows.size < 2:
            continue
        own = t[rows]
        out[rows, k] = make_filter(Steps.of(own), name)(columns[rows, k : k + 1], own)[:, 0]
    return out


#: Longest gap [s] :func:`on_clock` bridges, in the channel's own median intervals.
GAP_INTERVALS = 1.5


def on_clock(t: np.ndarray, values: np.ndarray, clock: np.ndarray) -> np.ndarray:
    """``values`` (n,) or (n, k), each column's finite samples at ``t`` interpolated
    linearly onto ``clock`` (NaN over a gap longer than :data:`GAP_INTERVALS` of the
    column's own median interval, and outside its span)."""
    columns = values.reshape(t.size, -1)
    out = np.full((clock.size, columns.shape[1]), np.nan)
    for k in range(columns.shape[1]):
        rows = np.isfinite(columns[:, k])
        if rows.sum() < 2:
            continue
        own = t[rows]
        gap = GAP_INTERVALS * float(np.median(np.diff(own)))
        out[:, k] = resample(own, columns[rows, k], clock, Method.LINEAR, gap)
    return out.reshape((clock.size, *values.shape[1:]))


def on_imu_clock(t: np.ndarray, acc: np.ndarray, *columns: np.ndarray | None) -> tuple:
    """``(clock, *columns)``: the IMU's own stamps (where ``acc[:, 0]``, ``ax``, has a
    sample) and each column :func:`on_clock` onto them (None kept)."""
    clock = t[np.isfinite(acc[:, 0])]
    return (clock, *(c if c is None else on_clock(t, c, clock) for c in columns))


def scored_reference(signals) -> np.ndarray | None:
    """A log's reference loads (n, 4) as the metrics score them: the log's own, or for
    channels on their own clocks each wheel's samples :func:`on_clock` onto every row (a
    transducer frame may carry one corner, so no row would hold all four)."""
    if signals.reference is None or not signals.own_clocks:
        return signals.reference
    return on_clock(signals.t, signals.reference, signals.t)
