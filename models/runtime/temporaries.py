"""Temporary files named by their owner, so that a crashed run's leftovers can be cleaned.

Every file written by renaming a temporary into place (outputs, the study
cache, the build cache) takes its temporary from :func:`temporary_file`. The
name says whose it is::

    .<stem>.wltmp-<host>-<pid>-<random><suffix>

(``host`` a short hash of the host name, ``pid`` the writing process; the
suffix is the target's, so writers that choose the format by suffix see the
right one). A ``try/finally`` removes the temporary on every exception,
including the ``KeyboardInterrupt`` of Ctrl-C and the exception the command
line raises on SIGTERM (:mod:`wheelload.studies.cli`). SIGKILL cannot be
caught, so :func:`remove_stale` runs when a folder is written next (on each
process's first write there): it removes the temporaries of this host whose
process is gone (or that are older than :data:`STALE_SECONDS`), and nothing else.

Example
-------
>>> path = temporary_file(Path("out"), "loads", ".csv")  # out/.loads.wltmp-1a2b3c4d-812-x9.csv
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import re
import socket
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

#: The mark of a temporary file in its name.
TAG = "wltmp"

#: A temporary older than this is stale even when its process id is alive (ids are reused).
STALE_SECONDS = 7 * 24 * 3600.0

_NAME = re.compile(rf"^\..*\.{TAG}-(?P<host>[0-9a-f]{{8}})-(?P<pid>\d+)-")


def _host() -> str:
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def is_stale(path: Path, *, now: float | None = None) -> bool:
    """True for a temporary of :func:`temporary_file` whose writer is gone (module docstring)."""
    match = _NAME.match(path.name)
    if match is None:
        return False
    try:
        age = (time.time() if now is None else now) - path.lstat().st_mtime
    except OSError:
        return False
    if age > STALE_SECONDS:
        return True
    return match["host"] == _host() and not _alive(int(match["pid"]))


def remove_stale(folder: Path) -> list[Path]:
    """Remove the stale temporaries in ``folder`` (:func:`is_stale`); the paths removed."""
    removed = []
    try:
        entries = list(Path(folder).iterdir())
    except OSError:
        return removed
    for path in entries:
        if is_stale(path):
            try:
                path.unlink()
            except OSError:
                continue  # gone already, or not ours to remove
            removed.append(path)
    return removed


@functools.cache
def _cleaned(folder: str) -> None:
    """:func:`remove_stale` once per folder and process (a fleet's output folder holds
    thousands of files: one scan, not one per file written)."""
    remove_stale(Path(folder))


def temporary_file(folder: Path, stem: str, suffix: str) -> Path:
    """A new empty file in ``folder`` named as a temporary of this process (module docstring).

    The folder's stale temporaries are removed first, on this process's first write
    there (:func:`remove_stale`).
    """
    folder = Path(folder)
    _cleaned(os.path.realpath(folder))
    handle, name = tempfile.mkstemp(
        prefix=f".{stem}.{TAG}-{_host()}-{os.getpid()}-", suffix=suffix, dir=folder
    )
    os.close(handle)
    return Path(name)


@contextlib.contextmanager
def replacing(path: Path, *, mode: int | None = None) -> Iterator[Path]:
    """A temporary beside ``path`` that replaces it when the block ends without error.

    The temporary (:func:`temporary_file`) gets the permissions of a new file under
    the umask (``mode`` instead, when given) and is removed whatever happens.

    Example
    -------
    >>> with replacing(Path("out/table.csv")) as temporary:
    ...     frame.to_csv(temporary, index=False)
    """
    path = Path(path)
    temporary = temporary_file(path.parent, path.stem, path.suffix)
    try:
        yield temporary
        if mode is None:
            mask = os.umask(0)
            os.umask(mask)
            mode = 0o666 & ~mask
        os.chmod(temporary, mode)
        temporary.replace(path)
    finally:
        temporary.unlink(missing_ok=True)
