"""What the dense and the chunked fit share: the loss, the robust weights, the rows' layout.

The rows of all data sets are stacked set after set, each set's used
samples in time order and, within a sample, its wheels in order (as
:func:`~wheelload.estimators.identification.regressors.evaluate` stacks
them); :class:`Layout` tells where each set's rows are and which wheel and
time each row has, from the data sets alone, so a fit that keeps only one
number per row (its residual) can compute the per-set scales.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from wheelload.estimators.identification.data import DataSet
from wheelload.estimators.identification.model import SuspensionFitModel
from wheelload.estimators.identification.regressors import CHUNK

ROBUST_SCALE = 1.5  # robust-loss threshold in units of the residual scale
INLIER = 3.0  # |r| / sigma below which a row counts for a robust fit's covariance


class FitLoss(enum.Enum):
    """Residual loss of the fit."""

    LINEAR = "linear"
    HUBER = "huber"
    SOFT_L1 = "soft-l1"


def robust_terms(e: np.ndarray, loss: FitLoss) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Cost :math:`\rho`, half its slope :math:`\psi` and the slope of that, :math:`h`, of the
    loss at scaled residuals ``e``, per row of ``scipy.optimize.least_squares``' cost
    :math:`C^2 \rho((e / C)^2)` (:math:`C` = :data:`ROBUST_SCALE`): Huber
    :math:`e^2` or :math:`2 C |e| - C^2`; soft-L1 :math:`2 C^2 (\sqrt{1 + (e/C)^2} - 1)`."""
    C = ROBUST_SCALE
    z = (e / C) ** 2
    if loss is FitLoss.HUBER:
        inside = np.abs(e) <= C
        cost = np.where(inside, e * e, 2 * C * np.abs(e) - C * C)
        return cost, np.where(inside, e, C * np.sign(e)), inside.astype(float)
    root = np.sqrt(1.0 + z)
    return 2 * C * C * (root - 1.0), e / root, 1.0 / (root * root * root)


#: Newton's method on a robust loss stops when no scaled parameter moves by more than this
#: (relative units), or after this many steps.
NEWTON_TOLERANCE = 1e-13
NEWTON_STEPS = 100
#: Relative change of the cost within rounding: a point whose cost is within this of the best
#: is as low, and counts as progress when it is nearer stationary (a smaller Newton decrement).
SETTLED = 1e-15
#: A step halved back to below this (scaled units) ends the steps: the cost is flat to
#: rounding there and no nearer stationary point is found (Huber's kink lets rows flip).
SETTLED_STEP = 1e-10


def newton(
    terms: Callable[[np.ndarray], tuple[float, np.ndarray, np.ndarray]],
    u: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:
    r"""Bounded Newton steps on a robust cost, halved while the cost grows.

    ``terms(u)`` gives the cost :math:`\sum \rho(A u - b)`, a triangular
    factor :math:`R` of the curvature :math:`A^\top \mathrm{diag}(h) A`
    and the gradient :math:`g = A^\top \psi` (:func:`robust_terms`); the
    step minimises :math:`\tfrac12 \|R \Delta\|^2 + g^\top \Delta` within the
    bounds, as the least squares :math:`\|R \Delta + R^{-\top} g\|` (BVLS).

    A step is kept when it lowers the cost, or leaves it equal to rounding with
    a smaller Newton decrement :math:`\|R^{-\top} g\|` (next to the minimiser
    the decrease, about :math:`g^\top \Delta`, is below the cost's rounding:
    judged on the cost alone the last step would be undone and the fit would
    end where the path to it happened to be, not at the minimiser).
    """
    best, previous, decrement = np.inf, u, np.inf
    for _ in range(NEWTON_STEPS):
        cost, R, gradient = terms(u)
        rhs = -np.linalg.lstsq(R.T, gradient, rcond=None)[0]
        lower_cost = cost < best - SETTLED * abs(best)
        nearer = cost <= best + SETTLED * abs(best) and np.linalg.norm(rhs) < decrement
        if not (lower_cost or nearer):
            moved = np.max(np.abs(u - previous))
            if moved <= SETTLED_STEP:  # at the minimiser to rounding (Huber's kink)
                return previous
            u = 0.5 * (u + previous)  # a step too long: back half way
            continue
        best, previous, decrement = min(cost, best), u, float(np.linalg.norm(rhs))
        step = optimize.lsq_linear(R, rhs, bounds=(lower - u, upper - u), method="bvls").x
        u = np.clip(u + step, lower, upper)
        if np.max(np.abs(step)) <= NEWTON_TOLERANCE:
            return u
    return u


def inliers(weighted: np.ndarray, loss: FitLoss) -> np.ndarray:
    """Rows that count for the covariance: all (least squares) or those with ``|r|/σ``
    below :data:`INLIER`."""
    return np.ones(weighted.size, bool) if loss is FitLoss.LINEAR else np.abs(weighted) < INLIER


@dataclass(frozen=True, eq=False)
class Inliers:
    r"""The rows that count for a robust fit's covariance (:func:`inliers` of
    :math:`r / \sigma_g`), from the residuals ``r`` and the per-set scales ``sigma``."""

    r: np.ndarray
    sigma: np.ndarray
    loss: FitLoss

    def of(self, rows: slice, group) -> np.ndarray:
        """The mask of ``rows``, all of set ``group`` (or one set index per row)."""
        return inliers(self.r[rows] / self.sigma[group], self.loss)


@dataclass(frozen=True, kw_only=True, eq=False)
class Layout:
    """Where each data set's rows are in the stacked rows (``offsets``), and their largest
    absolute target (``peak``)."""

    sets: tuple[DataSet, ...]
    offsets: np.ndarray  # (count + 1,) first row of each set
    peak: np.ndarray  # (count,) largest |y| of each set's rows

    @staticmethod
    def of(sets: tuple[DataSet, ...]) -> Layout:
        counts, peaks = [], []
        for data in sets:
            count, peak = 0, 0.0
            for start, stop in data.blocks(CHUNK):
                target = data.target[start:stop]
                finite = np.isfinite(target)
                count += int(finite.sum())
                if finite.any():
                    peak = max(peak, float(np.abs(target[finite]).max()))
            counts.append(count)
            peaks.append(peak)
        return Layout(
            sets=sets, offsets=np.concatenate([[0], np.cumsum(counts)]), peak=np.array(peaks)
        )

    @property
    def size(self) -> int:
        return int(self.offsets[-1])

    def rows(self, group: int) -> slice:
        return slice(int(self.offsets[group]), int(self.offsets[group + 1]))

    def row_blocks(self, group: int) -> Iterator[tuple[slice, np.ndarray, np.ndarray]]:
        """One set's rows a block of samples at a time: where they are among all rows, the
        wheel of each (index into the set's ``rows``) and its time."""
        data = self.sets[group]
        first = int(self.offsets[group])
        for start, stop in data.blocks(CHUNK):
            sample, wheel = np.nonzero(np.isfinite(data.target[start:stop]))
            yield slice(first, first + sample.size), wheel, data.t[start:stop][sample]
            first += sample.size


@dataclass(frozen=True, kw_only=True, eq=False)
class Problem:
    """What a fit's rows are built from: the model, the data, the start values ``theta``,
    the parameter scale (``|theta|``, 1 where 0) and whether instruments are wanted."""

    model: SuspensionFitModel
    sets: tuple[DataSet, ...]
    theta: np.ndarray
    scale: np.ndarray
    instrumented: bool


def instrument_columns(Z: np.ndarray, cols, scale, weight) -> np.ndarray:
    """Instrument regressors of the columns ``cols``, all lags side by side (lag-major),
    scaled and weighted per row."""
    block = Z[:, :, cols] * scale[cols] * weight[:, None, None]
    return block.reshape(block.shape[0], -1)
