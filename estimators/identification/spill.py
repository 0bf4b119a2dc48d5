"""Long identification data on disk: columns in an unnamed temporary file, mapped.

A data set or a per-row value of a fit longer than :data:`SPILL_BYTES` lives in
a temporary file mapped into memory (``mmap``, shared), so that the arrays are
ordinary NumPy arrays to the code that reads them. The pages a pass has read
stay mapped until :func:`release` drops them (``madvise(MADV_DONTNEED)``:
the values stay in the file and the page cache, the process no longer holds
them), which the chunked fit calls after each chunk: resident memory is then
the chunk a pass is at, whatever the log's length. The file has no name (it is
removed when the last array on it is freed, also after a crash).

Example
-------
>>> arrays = columns({"t": 1, "target": 4}, n)  # in memory when small
>>> arrays["target"][a:b] = block
>>> release(*arrays.values())
"""

from __future__ import annotations

import mmap
import tempfile

import numpy as np

#: Columns larger than this [bytes] are kept on disk; smaller ones in memory.
SPILL_BYTES = 64 << 20


def _map(size: int) -> mmap.mmap:
    """A shared read-write mapping of a new unnamed temporary file of ``size`` bytes."""
    with tempfile.TemporaryFile(prefix="wheelload-") as file:
        file.truncate(size)
        return mmap.mmap(file.fileno(), size)  # keeps a descriptor of its own


def columns(
    widths: dict[str, int], n: int, spill_bytes: int = SPILL_BYTES
) -> dict[str, np.ndarray]:
    """Float64 arrays (n, width) per name, uninitialised: in memory when their total is at
    most ``spill_bytes``, else on one temporary file (each column contiguous)."""
    size = 8 * n * sum(widths.values())
    if size == 0 or size <= spill_bytes:
        return {name: np.empty((n, width)) for name, width in widths.items()}
    shared = _map(size)
    arrays, offset = {}, 0
    for name, width in widths.items():
        flat = np.frombuffer(shared, dtype=np.float64, count=n * width, offset=offset)
        arrays[name] = flat.reshape(width, n).T
        offset += 8 * n * width
    return arrays


def row_values(n: int, spill_bytes: int = SPILL_BYTES) -> np.ndarray:
    """One float64 value per row (n,), on disk when longer than ``spill_bytes``."""
    return columns({"values": 1}, n, spill_bytes)["values"][:, 0]


def _mapping(array) -> mmap.mmap | None:
    base = array
    while isinstance(base, np.ndarray):
        base = base.base
    if isinstance(base, memoryview):
        base = base.obj
    return base if isinstance(base, mmap.mmap) else None


def release(*arrays) -> None:
    """Drop the pages of the arrays' files from this process (the values stay in the file
    and the page cache); arrays in memory are left alone."""
    if not hasattr(mmap, "MADV_DONTNEED"):  # (not Linux/BSD/macOS) the kernel decides
        return
    maps = {id(m): m for m in map(_mapping, arrays) if m is not None}
    for shared in maps.values():
        shared.madvise(mmap.MADV_DONTNEED)


def on_disk(array: np.ndarray) -> bool:
    """Whether ``array`` lives on a spill file."""
    return _mapping(array) is not None
