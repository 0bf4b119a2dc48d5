r"""The residuals' figures per data set, read a block of rows at a time.

The fit keeps one residual per row (in memory, or on disk for a long log:
:mod:`~wheelload.models.runtime.spill`) and reads it a block at a
time, so its memory does not grow with the log:

- the scale of a set's rows, :math:`\sigma_g = 1.4826\,\mathrm{MAD}` (median
  and median absolute deviation by exact selection over passes,
  :func:`~wheelload.estimators.kernels.order_statistics.blocked_median`);
- the lag-one autocorrelation of each wheel's residuals in time order,
  :math:`\rho = \sum e_k e_{k-1} / \sum e_k^2` of the centred series, its mean
  over the wheels clipped to [0, 0.99] (the AR(1) inflation of the errors);
- the RMSE per set and wheel, and the variance factor :math:`s^2`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

from wheelload.estimators.identification.fit_terms import FitLoss, Layout, inliers
from wheelload.estimators.kernels.order_statistics import blocked_median
from wheelload.models.runtime.spill import release

MAD_SCALE = 1.4826  # MAD to standard deviation of a normal distribution
BLOCK = 1 << 16  # rows per block


def _blocks(r: np.ndarray, rows: slice, transform=None) -> Callable[[], Iterator[np.ndarray]]:
    """A pass over ``r[rows]`` block by block (each through ``transform``), pages of a
    residual on disk dropped after each."""

    def blocks() -> Iterator[np.ndarray]:
        for start in range(rows.start, rows.stop, BLOCK):
            block = r[start : min(start + BLOCK, rows.stop)]
            yield block if transform is None else transform(block)
            release(r)

    return blocks


def scales(r: np.ndarray, layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """Each set's residual scale :math:`\\sigma_g` (MAD, at least 1e-9 of its largest
    target) and lag-one autocorrelation."""
    count = len(layout.sets)
    sigma, rho = np.ones(count), np.zeros(count)
    for g in range(count):
        rows = layout.rows(g)
        n = rows.stop - rows.start
        if n:
            centre = blocked_median(_blocks(r, rows), n)
            deviation = _blocks(r, rows, lambda b, centre=centre: np.abs(b - centre))
            spread = MAD_SCALE * blocked_median(deviation, n)
            sigma[g] = max(spread, 1e-9 * max(1.0, layout.peak[g]))
            rho[g] = _lag_one(r, layout, g)
    return sigma, rho


def _lag_one(r: np.ndarray, layout: Layout, group: int) -> float:
    """Lag-one autocorrelation of one set's residuals, per wheel in time order: streamed
    when each wheel's rows are already in time order (a drive log), else gathered and
    sorted (stable) first (a rig file's rows, short)."""
    wheels = len(layout.sets[group].rows)
    count, total = np.zeros(wheels), np.zeros(wheels)
    latest, ordered = np.full(wheels, -np.inf), True
    for rows, wheel, t in layout.row_blocks(group):
        block = r[rows]
        count += np.bincount(wheel, minlength=wheels)
        total += np.bincount(wheel, weights=block, minlength=wheels)
        for w in np.unique(wheel):
            times = t[wheel == w]
            ordered &= bool(times[0] >= latest[w] and np.all(np.diff(times) >= 0))
            latest[w] = times[-1]
        release(r)
    mean = total / np.maximum(count, 1)

    def in_order() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        if ordered:
            for rows, wheel, _ in layout.row_blocks(group):
                yield r[rows], wheel
                release(r)
            return
        parts = [(r[rows], wheel, t) for rows, wheel, t in layout.row_blocks(group)]
        values, wheel, t = (np.concatenate(p) for p in zip(*parts))
        order = np.lexsort((t, wheel))  # by wheel, then time; stable
        yield values[order], wheel[order]

    square, lagged = np.zeros(wheels), np.zeros(wheels)
    previous = np.full(wheels, np.nan)
    for block, wheel in in_order():
        for w in np.unique(wheel):
            e = block[wheel == w] - mean[w]
            square[w] += np.dot(e, e)
            lagged[w] += np.dot(e[1:], e[:-1]) + (
                0.0 if np.isnan(previous[w]) else previous[w] * e[0]
            )
            previous[w] = e[-1]
    used = (count > 2) & (square > 0)
    if not used.any():
        return 0.0
    return float(np.clip(np.mean(lagged[used] / square[used]), 0.0, 0.99))


def rmse(r: np.ndarray, layout: Layout) -> dict[tuple[str, str], float]:
    """RMSE [N] of the residuals per (data set, wheel) with rows."""
    table = {}
    for g, data in enumerate(layout.sets):
        wheels = len(data.rows)
        count, square = np.zeros(wheels), np.zeros(wheels)
        for rows, wheel, _ in layout.row_blocks(g):
            block = r[rows]
            count += np.bincount(wheel, minlength=wheels)
            square += np.bincount(wheel, weights=block * block, minlength=wheels)
            release(r)
        for w in np.flatnonzero(count):
            table[(data.label(), data.rows[w])] = float(np.sqrt(square[w] / count[w]))
    return table


def variance_factor(
    r: np.ndarray, sigma: np.ndarray, layout: Layout, free: int, loss: FitLoss
) -> float:
    """:math:`s^2`: the mean squared scaled residual :math:`(r / \\sigma_g)^2` of the rows
    that count (:func:`~.fit_terms.inliers`), per degree of freedom."""
    total, counted = 0.0, 0
    for g in range(len(layout.sets)):
        for block in _blocks(r, layout.rows(g), lambda b, g=g: b / sigma[g])():
            keep = inliers(block, loss)
            total += float(np.sum(block[keep] ** 2))
            counted += int(keep.sum())
    return total / max(counted - free, 1)
