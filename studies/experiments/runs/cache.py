"""Results cached on disk by a hash of their inputs.

The key of a unit of work is the SHA-256 of its kind, its settings (which
carry the vehicle file's bytes, the scenario, the seed ...) and the code
version: the hash of every Python source file of the installed ``wheelload``
package, so that any change of the code recomputes everything and a rerun
with nothing changed recomputes nothing. Values are stored as data, never
code (:mod:`~wheelload.studies.experiments.runs.cache_entries`), in a folder of
mode 0700, written to a temporary file and renamed (a crash never leaves half
a file under a key). An entry that is truncated, damaged, of another key or
not written by this user is recomputed with a one-line note, never trusted.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import os
import stat
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from wheelload.models.runtime.temporaries import temporary_file
from wheelload.studies.experiments.runs.cache_entries import (
    CacheEntryError,
    read_entry,
    write_entry,
)

_log = logging.getLogger(__name__)


@cache
def code_version() -> str:
    """SHA-256 over the relative paths and bytes of the package's ``.py`` files."""
    digest = hashlib.sha256()
    root = Path(str(resources.files("wheelload.models"))).parent
    for folder in ("models", "estimators", "studies"):
        for path in sorted((root / folder).rglob("*.py")):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"__type__": type(value).__qualname__, **fields}
    if isinstance(value, tuple | list):
        return [_plain(item) for item in value]
    if isinstance(value, float | int | str | bool) or value is None:
        return value
    if hasattr(value, "value") and hasattr(value, "name"):  # enum member
        return f"{type(value).__qualname__}.{value.name}"
    raise TypeError(f"cannot hash a {type(value).__name__} in a cache key")


def cache_key(kind: str, spec: Any) -> str:
    """The hex key of a unit of work: its kind, its settings and the code version."""
    text = json.dumps({"kind": kind, "spec": _plain(spec), "code": code_version()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


#: What :meth:`ResultCache.get` returns for a key with no usable entry.
MISSING = object()


class CacheFolderError(ValueError):
    """A cache folder that cannot be trusted: names it and the fix."""


def private_folder(folder: Path) -> Path:
    """``folder`` made (mode 0700) or checked: a folder of this user that others cannot
    enter; a folder of this user open to others is closed with a note; a symbolic link or
    a folder of another user is a :class:`CacheFolderError`."""
    folder = Path(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    try:
        folder.mkdir(mode=0o700)
        os.chmod(folder, 0o700)  # mkdir's mode is filtered by the umask
        return folder
    except FileExistsError:
        pass
    info = folder.lstat()
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        what = "a symbolic link" if stat.S_ISLNK(info.st_mode) else "not a folder"
        raise CacheFolderError(
            f"{folder}: the study cache is {what}: remove it or give --cache a folder of your own"
        )
    if info.st_uid != os.getuid():
        raise CacheFolderError(
            f"{folder}: the study cache belongs to user {info.st_uid}: "
            "give --cache a folder of your own"
        )
    mode = stat.S_IMODE(info.st_mode)
    if mode & 0o077:
        os.chmod(folder, 0o700)
        _log.warning("wheelload: note: study cache %s had mode %o: made private", folder, mode)
    return folder


@dataclasses.dataclass(frozen=True, kw_only=True)
class ResultCache:
    """A private folder (mode 0700) of results named by key, stored as data only
    (:mod:`wheelload.studies.experiments.runs.cache_entries`: NPZ without pickles and JSON)."""

    folder: Path

    def path(self, key: str) -> Path:
        return Path(self.folder) / f"{key}.npz"

    def has(self, key: str) -> bool:
        return self.path(key).is_file()

    def load(self, key: str) -> Any:
        """The entry of ``key``; a :class:`CacheEntryError` when it is missing, not a file of
        this user, truncated, damaged or of another key."""
        path = self.path(key)
        try:
            info = path.lstat()
        except OSError:
            raise CacheEntryError(f"{path}: no such cache entry") from None
        if not stat.S_ISREG(info.st_mode):
            raise CacheEntryError(f"{path}: not a regular file")
        if info.st_uid != os.getuid():
            raise CacheEntryError(f"{path}: written by user {info.st_uid}, not by you")
        return read_entry(path, key)

    def get(self, key: str) -> Any:
        """The entry of ``key``, or :data:`MISSING` when there is none or it cannot be used
        (a one-line note says why: it is computed again and replaced)."""
        private_folder(Path(self.folder))
        if not os.path.lexists(self.path(key)):
            return MISSING
        try:
            return self.load(key)
        except CacheEntryError as error:
            _log.warning("wheelload: note: cache entry %s: recomputed", error)
            return MISSING

    def store(self, key: str, value: Any) -> None:
        """Write ``value`` through a temporary file renamed into place (never half a file)."""
        folder = private_folder(Path(self.folder))
        temporary = temporary_file(folder, key, ".npz")
        try:
            write_entry(temporary, key, value)
            os.replace(temporary, self.path(key))
        finally:
            temporary.unlink(missing_ok=True)
