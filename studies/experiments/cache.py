"""Results cached on disk by a hash of their inputs.

The key of a unit of work is the SHA-256 of its kind, its settings (which
carry the vehicle file's bytes, the scenario, the seed ...) and the code
version: the hash of every Python source file of the installed ``wheelload``
package, so that any change of the code recomputes everything and a rerun
with nothing changed recomputes nothing. Values are pickled, written to a
temporary file in the cache folder and renamed (a crash never leaves half a
file under a key).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pickle
import tempfile
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any


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


@dataclasses.dataclass(frozen=True, kw_only=True)
class ResultCache:
    """A folder of pickled results named by key."""

    folder: Path

    def path(self, key: str) -> Path:
        return Path(self.folder) / f"{key}.pkl"

    def has(self, key: str) -> bool:
        return self.path(key).is_file()

    def load(self, key: str) -> Any:
        with self.path(key).open("rb") as stream:
            return pickle.load(stream)

    def store(self, key: str, value: Any) -> None:
        folder = Path(self.folder)
        folder.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(suffix=".tmp", prefix=".", dir=folder)
        try:
            with os.fdopen(handle, "wb") as stream:
                pickle.dump(value, stream, protocol=pickle.HIGHEST_PROTOCOL)
            Path(name).replace(self.path(key))
        finally:
            Path(name).unlink(missing_ok=True)
