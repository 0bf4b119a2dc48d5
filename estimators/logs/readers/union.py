"""Channels on their own clocks as one long table: the union of their time stamps.

Each row is a time at which at least one channel has a sample; a channel's
column holds its value at its own time stamps and NaN at every other row (no
new value then: a missing sample, whose update the filter skips). Signals of
one CAN frame share its time stamp and so one row. Time stamps closer than
:data:`~wheelload.estimators.logs.readers.resample.TIME_TOLERANCE` are one row.
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.logs.readers.resample import TIME_TOLERANCE


def union_clock(stamps: list[np.ndarray]) -> np.ndarray:
    """The sorted union of finite time stamps, those within the tolerance merged."""
    finite = [np.asarray(t, float)[np.isfinite(t)] for t in stamps]
    every = np.sort(np.concatenate(finite)) if finite else np.zeros(0)
    if every.size == 0:
        return every
    keep = np.concatenate([[True], np.diff(every) > TIME_TOLERANCE])
    return every[keep]


def on_union(t: np.ndarray, values: np.ndarray, clock: np.ndarray) -> np.ndarray:
    """``values`` at their stamps ``t`` placed on the rows of ``clock`` (NaN elsewhere).

    ``clock`` holds every finite stamp of ``t`` (:func:`union_clock`); of two samples on
    one row, the later one is kept.
    """
    t = np.asarray(t, float)
    values = np.asarray(values, float)
    keep = np.isfinite(t)
    out = np.full(clock.shape, np.nan)
    rows = np.searchsorted(clock, t[keep] - TIME_TOLERANCE, side="left")
    out[rows] = values[keep]
    return out
