"""The errors of a log's scored samples, kept for the summary's figures (eq. 31-34).

The 95th percentile needs every error. A short log's errors stay in memory (one row a
wheel); beyond :data:`MEMORY_LIMIT` they go to files in a private temporary folder as
they come (one a wheel, removed when the figures are made), so that the memory of
``wheelload estimate`` on a long log is a wheel's column, not the whole store. The figures
are those of :func:`~wheelload.studies.metrics.metrics_table` to the bit (the pooled RMSE
summed one wheel at a time: 1e-15 relative): per wheel the same operations on the same
numbers; the pooled 95th percentile from the wheels' sorted columns by selection of its
two order statistics (:func:`order_statistic`) and NumPy's own interpolation
(:func:`~wheelload.estimators.kernels.order_statistics.linear_percentile`).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from wheelload.estimators import linear_percentile, percentile

#: Bytes of errors kept in memory; a longer log's go to disk (64 MiB: 2 M samples, 4 wheels).
MEMORY_LIMIT = 64 * 2**20
PERCENTILE = 95.0
#: Rows held at first when the log's length is not known (doubled as they come).
FIRST_ROWS = 1 << 16


def order_statistic(columns: list[np.ndarray], k: int) -> float:
    """The k-th smallest (from 0) of the values of sorted, non-negative ``columns``, found
    by bisection on the values' bit patterns (which order non-negative floats), each count
    a binary search per column: a few pages of each column are read, however long."""
    low, high = 0, int(np.array(max(float(c[-1]) for c in columns if len(c))).view(np.int64))
    while low < high:
        middle = (low + high) // 2
        value = np.array(middle, np.int64).view(np.float64)
        if sum(int(np.searchsorted(c, value, side="right")) for c in columns) > k:
            high = middle
        else:
            low = middle + 1
    return float(np.array(low, np.int64).view(np.float64))


class ErrorStore:
    """The errors of ``wheels`` columns, ``samples`` rows (None: not known, grown as they
    come), appended chunk by chunk."""

    def __init__(self, wheels: int, samples: int | None, memory_limit: int | None = None) -> None:
        self.wheels = wheels
        self.count = 0
        self._rows = None
        self._folder = None
        self.limit = MEMORY_LIMIT if memory_limit is None else memory_limit
        known = samples is not None  # not known: grown as they come, to files beyond the limit
        rows = samples if known else min(FIRST_ROWS, self.limit // (8 * wheels))
        if (known or rows > 0) and wheels * rows * 8 <= self.limit:
            self._rows = np.empty((wheels, rows))  # one contiguous row a wheel
        else:
            self._to_files()

    @property
    def on_disk(self) -> bool:
        """Whether the errors go to files."""
        return self._rows is None

    def _to_files(self) -> None:
        """Keep the errors on disk from now on (those held so far written first)."""
        self._folder = tempfile.TemporaryDirectory(prefix="wheelload-errors-")
        self._paths = [Path(self._folder.name) / f"wheel{i}.f8" for i in range(self.wheels)]
        self._files = [path.open("wb") for path in self._paths]
        if self._rows is not None:
            for i, file in enumerate(self._files):
                file.write(self._rows[i, : self.count].tobytes())
            self._rows = None

    def append(self, errors: np.ndarray) -> None:
        """Take the next chunk's errors, (count, wheels)."""
        m = len(errors)
        if self._rows is not None and self.count + m > self._rows.shape[1]:
            size = max(2 * self._rows.shape[1], self.count + m)
            if self.wheels * size * 8 <= self.limit:
                grown = np.empty((self.wheels, size))
                grown[:, : self.count] = self._rows[:, : self.count]
                self._rows = grown
            else:
                self._to_files()
        if self._rows is not None:
            self._rows[:, self.count : self.count + m] = errors.T
        else:
            for i, file in enumerate(self._files):
                file.write(np.ascontiguousarray(errors[:, i]).tobytes())
        self.count += m

    def rows(self, means: np.ndarray) -> list[list[float]]:
        """RMSE, RMSE %, P95 and Max of each wheel (``means``: the reference's mean load
        per wheel), then pooled. Once only: the store is overwritten, then released."""
        rows, squares, columns = [], 0.0, []
        try:
            for i in range(self.wheels):
                column = self._column(i)
                row, square_sum = _wheel_row(column, float(means[i]))
                rows.append(row)
                squares += square_sum
                column.sort()  # for the pooled percentile's selection
                if self._rows is None:
                    column.tofile(self._paths[i])
                    del column
                    columns.append(np.memmap(self._paths[i], np.float64, mode="r"))
                else:
                    columns.append(column)
            total = self.count * self.wheels
            rmse = float(np.sqrt(squares / total))
            p95 = linear_percentile(total, PERCENTILE, lambda k: order_statistic(columns, k))
            peak = float(max(row[3] for row in rows))
            rows.append([rmse, 100.0 * rmse / float(means.mean()), p95, peak])
            return rows
        finally:
            columns.clear()  # the files' maps closed before the folder goes
            self.release()

    def _column(self, i: int) -> np.ndarray:
        if self._rows is not None:
            return self._rows[i, : self.count]  # a view: overwritten in place
        self._files[i].close()
        return np.fromfile(self._paths[i], np.float64)

    def release(self) -> None:
        """Remove the files of a store on disk (also when the figures are never made)."""
        if self._folder is not None:
            for file in self._files:
                file.close()
            self._folder.cleanup()
            self._folder = None


def _wheel_row(column: np.ndarray, mean: float) -> tuple[list[float], float]:
    """One wheel's RMSE, RMSE %, P95 and Max of errors ``column`` (overwritten: made
    absolute, then partitioned by the percentile) and its sum of squares, computed as
    :func:`~wheelload.studies.metrics.metrics_table` does, without a whole-size temporary
    where :func:`_squares_invert` allows."""
    np.abs(column, out=column)
    peak = float(column.max())
    if _squares_invert(column, peak):  # squared in place, then back: no temporary
        np.square(column, out=column)
        rmse = float(np.sqrt(np.mean(column)))
        squares = float(np.sum(column))
        np.sqrt(column, out=column)  # |e| again, exactly (_squares_invert)
    else:
        square = column * column
        rmse = float(np.sqrt(np.mean(square)))
        squares = float(np.sum(square))
        del square
    p95 = percentile(column, PERCENTILE, overwrite_input=True)
    return [rmse, 100.0 * rmse / mean, p95, peak], squares


def _squares_invert(column: np.ndarray, peak: float) -> bool:
    """Whether ``sqrt(e * e) == e`` for every ``e`` of ``column`` (all >= 0, max ``peak``).

    In binary floating point with round-to-nearest, the square root of a rounded
    square gives the number back exactly unless the square overflows or leaves the
    normal range (Boldo, "Stupid is as stupid does: taking the square root of the
    square of a floating-point number", 2015); errors in newtons are far inside it.
    """
    if not peak < 1e150:
        return False
    return bool(np.min(column, where=column > 0.0, initial=np.inf) > 1e-150)
