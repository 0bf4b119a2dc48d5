"""Columns kept on disk (estimators/identification/spill.py): real temporary files mapped,
their pages dropped from the process after a pass, the values kept."""

import mmap
from pathlib import Path

import numpy as np
import pytest

from wheelload.estimators.kf.tuning import MAX_INTERVAL, nominal_interval
from wheelload.estimators.types import Steps
from wheelload.models.runtime.spill import Appended, columns, on_disk, release, row_values

STATUS = Path("/proc/self/status")


def _resident_mb() -> float:
    """This process's resident memory now (``VmRSS``) [MB]."""
    line = next(x for x in STATUS.read_text().splitlines() if x.startswith("VmRSS:"))
    return int(line.split()[1]) / 1024.0


def test_small_columns_stay_in_memory_and_large_ones_go_to_disk():
    small = columns({"t": 1, "target": 4}, 1000, spill_bytes=40_000)
    large = columns({"t": 1, "target": 4}, 1000, spill_bytes=39_999)
    assert not any(on_disk(a) for a in small.values())
    assert all(on_disk(a) for a in large.values())
    assert large["target"].shape == (1000, 4) and large["t"].shape == (1000, 1)
    assert on_disk(row_values(10, spill_bytes=0)) and not on_disk(row_values(10))


@pytest.mark.skipif(
    not STATUS.exists() or not hasattr(mmap, "MADV_DONTNEED"),
    reason="needs /proc/self/status and madvise(MADV_DONTNEED) (Linux)",
)
def test_released_pages_leave_the_process_and_the_values_stay():
    """64 MB written through the mapping are resident until released; afterwards the
    process holds less than 8 MB of them, and every value reads back."""
    n = 8 << 20
    values = row_values(n, spill_bytes=0)
    before = _resident_mb()
    values[:] = np.arange(n, dtype=float)
    written = _resident_mb()
    release(values)
    released = _resident_mb()
    assert written - before > 56.0
    assert released - before < 8.0
    assert values[12345] == 12345.0 and values[-1] == n - 1
    assert np.array_equal(values[::4096], np.arange(0, n, 4096, dtype=float))


def test_an_appended_column_goes_to_disk_past_its_limit_with_the_same_values():
    rng = np.random.default_rng(5)
    parts = [rng.normal(size=int(k)) for k in rng.integers(1, 900, 40)]
    for limit, disk in ((10**9, False), (8 * 2000, True)):
        column = Appended(spill_bytes=limit)
        for part in parts:
            column.append(part)
        values = column.array()
        assert on_disk(values) == disk
        assert np.array_equal(values, np.concatenate(parts))


def test_the_steps_of_time_stamps_on_disk_are_numpys():
    """:class:`Steps` of a time column on disk, read a block at a time: the median and
    largest deviation of ``np.diff`` (300 001 stamps: past a block of 65 536)."""
    rng = np.random.default_rng(9)
    t = np.cumsum(0.01 + rng.uniform(-4e-4, 4e-4, 300_001))
    stored = row_values(t.size, spill_bytes=0)
    stored[:] = t
    steps = Steps.of(stored)
    dt = np.diff(t)
    assert steps.median == np.median(dt)
    assert steps.deviation == np.max(np.abs(dt - np.median(dt)))
    assert steps.uniform() and not Steps.of(np.array([0.0, 1.0, 3.0])).uniform()


def test_the_nominal_interval_of_time_stamps_on_disk_is_numpys():
    """The KF's interval (median of the positive finite steps below MAX_INTERVAL) of a
    time column on disk with gaps and a missing stamp: numpy's median of those steps."""
    rng = np.random.default_rng(11)
    t = np.cumsum(rng.uniform(0.005, 0.015, 200_001))
    t[70_000:] += 5.0  # a gap past MAX_INTERVAL
    t[123_456] = np.nan
    stored = row_values(t.size, spill_bytes=0)
    stored[:] = t
    dt = np.diff(t)
    expected = np.median(dt[np.isfinite(dt) & (dt > 0) & (dt < MAX_INTERVAL)])
    assert nominal_interval(stored) == expected
