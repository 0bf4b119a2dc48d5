"""One ``wheelload study`` at a time in an output folder: a lock taken before any work.

:func:`folder_lock` takes an exclusive ``flock`` on ``DIR/.wheelload-study.lock``
without waiting; a second study into the same folder is refused at once with
one line naming the folder and the process that holds it. The kernel drops
the lock when its process ends, however it ends (even SIGKILL), so a crashed
run never leaves a folder locked; the small lock file stays (removing it
would let two runs lock two different files).

Example
-------
>>> with folder_lock(Path("out")):
...     run_study("iso-dlc", context)
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

#: The lock file's name in the output folder.
LOCK_NAME = ".wheelload-study.lock"


class FolderLockedError(ValueError):
    """Another study writes into the folder: names it, the holder and the fix."""


@contextlib.contextmanager
def folder_lock(folder: Path) -> Iterator[None]:
    """Hold the study lock of ``folder`` (module docstring) for the ``with`` block."""
    path = Path(folder) / LOCK_NAME
    handle = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(handle, 64, 0).decode("ascii", "replace").strip() or "?"
            raise FolderLockedError(
                f"{folder}: another 'wheelload study' (pid {holder}) is writing into this "
                "folder: wait for it to finish or give another --out"
            ) from None
        os.ftruncate(handle, 0)
        os.pwrite(handle, f"{os.getpid()}\n".encode("ascii"), 0)
        yield
    finally:
        os.close(handle)
