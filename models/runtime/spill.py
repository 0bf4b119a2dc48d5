"""Long logs' columns on disk: an unnamed temporary file, mapped.

A column longer than :data:`SPILL_BYTES` (a long log's time stamps, an
identification data set, a fit's per-row residuals) lives in a temporary file
mapped into memory (``mmap``, shared), so that the arrays are ordinary NumPy
arrays to the code that reads them. The pages a pass has read stay mapped
until :func:`release` drops them (``madvise(MADV_DONTNEED)``: the values stay
in the file and the page cache, the process no longer holds them), which a
pass over a long log calls after each block: resident memory is then the
block a pass is at, whatever the log's length. The file has no name (it is
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


class Appended:
    """A float64 column appended chunk by chunk, its length not known in advance: in
    memory up to ``spill_bytes``, beyond that written to a temporary file as it comes."""

    def __init__(self, spill_bytes: int = SPILL_BYTES) -> None:
        self.spill_bytes = spill_bytes
        self.parts: list[np.ndarray] = []
        self.size = 0
        self.file = None

    def append(self, values: np.ndarray) -> None:
        values = np.ascontiguousarray(values, dtype=np.float64)
        self.size += values.size
        if self.file is None:
            self.parts.append(values)
            if 8 * self.size > self.spill_bytes:
                self.file = tempfile.TemporaryFile(prefix="wheelload-")
                for part in self.parts:
                    self.file.write(part.tobytes())
                self.parts = []
        else:
            self.file.write(values.tobytes())

    def array(self) -> np.ndarray:
        """The column (n,): on its file, mapped, when it went there."""
        if self.file is None:
            return np.concatenate(self.parts) if self.parts else np.zeros(0)
        self.file.flush()
        shared = mmap.mmap(self.file.fileno(), 8 * self.size)
        self.file.close()
        return np.frombuffer(shared, dtype=np.float64)


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
