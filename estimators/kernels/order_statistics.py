"""Median and percentile as numpy computes them, without the ``numpy.ma`` import.

NumPy 2 imports ``numpy.ma`` (about 10 ms, a fortieth of a warm ``wheelload
estimate``) on the first ``np.median``, ``np.nanmedian`` or ``np.percentile``
(their NaN checks and ``np.unique`` ask ``np.ma``). These give the same numbers
to the bit: the order statistics from ``np.partition`` (in place where the caller
allows: no copy of a long column), the middle pair's mean :math:`(a + b)/2`, and
the percentile's linear interpolation (method 7 of Hyndman and Fan) in numpy's own
floating-point steps (:func:`linear_percentile`); NaN where any value is NaN. The
test suite compares them with numpy on random data.

Example
-------
>>> median(np.diff(t))  # np.median(np.diff(t))
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np


def median(values, axis: int | None = None, *, overwrite_input: bool = False):
    """``np.median(values, axis)`` for ``axis`` None (flattened) or the last axis;
    ``overwrite_input`` lets it partition ``values`` (a float64 array) in place."""
    x = np.asarray(values, dtype=float)
    if axis is None:
        x = x.reshape(-1)
    elif axis not in (-1, x.ndim - 1):
        raise ValueError(f"median along axis {axis} of a {x.ndim}-d array: use the last axis")
    n = x.shape[-1]
    if n == 0:
        return np.float64(np.nan) if x.ndim == 1 else np.full(x.shape[:-1], np.nan)
    half = n // 2
    kth = [half - 1, half, n - 1] if n % 2 == 0 else [half, n - 1]  # n - 1: NaN sorts last
    if overwrite_input:
        x.partition(kth, axis=-1)
        part = x
    else:
        part = np.partition(x, kth, axis=-1)
    middle = part[..., half]
    if n % 2 == 0:
        middle = (part[..., half - 1] + middle) / 2.0  # np.mean of the middle pair
    nan = np.isnan(part[..., n - 1])
    if x.ndim == 1:
        return np.float64(np.nan) if nan else np.float64(middle)
    return np.where(nan, np.nan, middle)


def nanmedian(values, *, overwrite_input: bool = False):
    """``np.nanmedian(values)`` of 1-D ``values``: the median of the values that are not NaN
    (with ``overwrite_input``, moved together in place, as numpy's)."""
    x = np.asarray(values, dtype=float).reshape(-1)
    nan = np.isnan(x)
    missing = np.flatnonzero(nan)
    if missing.size == x.size:
        return np.float64(np.nan)
    if missing.size == 0:
        return median(x, overwrite_input=overwrite_input)
    if not overwrite_input:
        x = x.copy()
    tail = x[-missing.size :][~nan[-missing.size :]]  # the values after the last gap
    x[missing[: tail.size]] = tail
    return median(x[: -missing.size], overwrite_input=True)


def linear_percentile(n: int, q: float, value_at: Callable[[int], float]) -> float:
    """``np.percentile(x, q)`` (method ``linear``) of ``n`` values given their order
    statistics ``value_at(k)`` (the k-th smallest, from 0): NumPy's virtual index
    :math:`(n - 1) q / 100` and its two-sided interpolation, operation for operation."""
    virtual = (n - 1) * float(np.true_divide(q, 100))
    previous = int(np.floor(virtual))
    if virtual >= n - 1:
        return float(value_at(n - 1))
    gamma = virtual - previous
    low, high = float(value_at(previous)), float(value_at(previous + 1))
    difference = high - low
    return high - difference * (1.0 - gamma) if gamma >= 0.5 else low + difference * gamma


def percentile(values, q: float, *, overwrite_input: bool = False) -> float:
    """``np.percentile(values, q)`` of 1-D ``values`` (``q`` in percent, method ``linear``);
    ``overwrite_input`` lets it partition ``values`` (a float64 array) in place."""
    if not 0.0 <= q <= 100.0:
        raise ValueError("Percentiles must be in the range [0, 100]")
    x = np.asarray(values, dtype=float).reshape(-1)
    n = x.size
    if n == 0:
        return float("nan")
    previous = min(int(np.floor((n - 1) * float(np.true_divide(q, 100)))), n - 1)
    part = x if overwrite_input else x.copy()
    part.partition(sorted({previous, min(previous + 1, n - 1), n - 1}))
    if np.isnan(part[n - 1]):  # NaN sorts last
        return float("nan")
    return linear_percentile(n, q, part.__getitem__)


#: Values gathered into memory at once by :func:`blocked_kth` (8 MB).
GATHER = 1 << 20
#: Bins of one histogram pass of :func:`blocked_kth`.
BINS = 4096


def blocked_kth(
    blocks: Callable[[], Iterator[np.ndarray]], n: int, k: int, gather: int = GATHER
) -> float:
    """The ``k``-th smallest (from 0) of ``n`` values (no NaN) that ``blocks()`` gives
    block by block, each call a new pass, in memory ``gather`` values at most.

    Exact selection by histogram: a pass counts the values in the interval known to
    hold the answer; when few enough, they are gathered and partitioned, else a
    second pass bins them (:data:`BINS` equal bins between their extremes) and the
    bin holding rank ``k`` becomes the interval. A pass reads every block once.
    """
    if n <= gather:
        values = np.concatenate([np.asarray(b, float).ravel() for b in blocks()])
        return float(np.partition(values, k)[k])
    infinite = [(int(np.sum(b == -np.inf)), int(np.sum(b == np.inf))) for b in blocks()]
    negative, positive = (sum(c) for c in zip(*infinite))
    if k < negative or k >= n - positive:
        return -np.inf if k < negative else np.inf
    largest_float = np.finfo(float).max
    # the answer is in [low, high]; `below` values lie under it
    low, high, below = -largest_float, largest_float, negative
    while True:
        inside, smallest, largest = 0, np.inf, -np.inf
        for block in blocks():
            chosen = block[(block >= low) & (block <= high)]
            if chosen.size:
                inside += chosen.size
                smallest, largest = min(smallest, chosen.min()), max(largest, chosen.max())
        if smallest == largest:
            return float(smallest)
        if inside <= gather:
            values = np.concatenate([b[(b >= low) & (b <= high)] for b in blocks()])
            return float(np.partition(values, k - below)[k - below])
        edges = np.linspace(smallest, largest, BINS + 1)
        counts = np.zeros(BINS, np.int64)
        for block in blocks():
            chosen = block[(block >= low) & (block <= high)]
            bins = np.minimum(np.searchsorted(edges, chosen, side="right") - 1, BINS - 1)
            counts += np.bincount(bins, minlength=BINS)
        cumulative = np.cumsum(counts)
        b = int(np.searchsorted(cumulative, k - below, side="right"))
        below += int(cumulative[b - 1]) if b else 0
        last = b == BINS - 1  # the last bin holds its upper edge
        low, high = edges[b], edges[b + 1] if last else np.nextafter(edges[b + 1], -np.inf)


def blocked_median(
    blocks: Callable[[], Iterator[np.ndarray]], n: int, gather: int = GATHER
) -> float:
    """``np.median`` of ``n`` values (no NaN) given block by block (:func:`blocked_kth`)."""
    half = n // 2
    if n % 2:
        return blocked_kth(blocks, n, half, gather)
    if n <= gather:  # one gather, numpy's numbers to the bit
        return float(median(np.concatenate([np.asarray(b, float).ravel() for b in blocks()])))
    pair = blocked_kth(blocks, n, half - 1, gather), blocked_kth(blocks, n, half, gather)
    return (pair[0] + pair[1]) / 2.0
