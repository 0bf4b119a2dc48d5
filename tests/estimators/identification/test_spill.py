"""Columns kept on disk (estimators/identification/spill.py): real temporary files mapped,
their pages dropped from the process after a pass, the values kept."""

import mmap
from pathlib import Path

import numpy as np
import pytest

from wheelload.estimators.identification.spill import columns, on_disk, release, row_values

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
