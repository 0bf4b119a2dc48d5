"""A cache entry holds data, never code: NPZ arrays (no pickles) and a JSON manifest.

:func:`encode` turns a study result into named arrays plus one JSON tree,
which :func:`write_entry` saves as an uncompressed NPZ file (the manifest as
the ``manifest`` array of UTF-8 bytes). :func:`read_entry` loads it with
``allow_pickle=False`` and rebuilds the value: only JSON scalars, lists,
tuples, string-keyed dicts, numeric, boolean or string arrays, DataFrames of
such columns, and the dataclasses named in :data:`VALUE_TYPES`. Nothing in a
file can make the loader run code or import a module of its choice; a file
that is truncated, damaged (the ZIP members carry a CRC-32), written under
another key or in another format is a :class:`CacheEntryError`.

Example
-------
>>> write_entry(Path("out/.cache/k.npz"), "k", frame)
>>> read_entry(Path("out/.cache/k.npz"), "k").equals(frame)
True
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

#: The format written in every manifest (a file of another format is not read).
FORMAT = "wheelload-cache-1"

#: The dataclasses an entry may hold, as ``module:qualname`` (the decoder imports these only).
VALUE_TYPES = ("wheelload.studies.experiments.runs.units:TrialResult",)


class CacheEntryError(ValueError):
    """A cache entry that cannot be used: names the file and why."""


def _name(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _plain_array(array: np.ndarray) -> tuple[np.ndarray, bool]:
    """``array`` as an array NPZ stores without pickles; True when it held Python strings."""
    if array.dtype.hasobject:
        items = array.ravel().tolist()
        if not all(isinstance(item, str) for item in items):
            raise TypeError("a cache entry holds object arrays of strings only")
        return np.array(items, dtype=str).reshape(array.shape), True
    if array.dtype.kind not in "biufcUS":
        raise TypeError(f"a cache entry cannot hold arrays of dtype {array.dtype}")
    return array, False


class _Encoder:
    def __init__(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}

    def array(self, array: np.ndarray) -> dict:
        plain, text = _plain_array(np.asarray(array))
        name = f"a{len(self.arrays)}"
        self.arrays[name] = plain
        return {"array": name, "text": text}

    def index(self, index) -> dict:
        import pandas as pd

        if isinstance(index, pd.MultiIndex):
            raise TypeError("a cache entry cannot hold a MultiIndex")
        if isinstance(index, pd.RangeIndex):
            return {"range": [index.start, index.stop, index.step], "name": index.name}
        return {"index": self.array(index.to_numpy()), "name": index.name}

    def node(self, value: Any) -> Any:
        import pandas as pd

        if value is None or isinstance(value, bool | int | float | str):
            return value
        if isinstance(value, np.ndarray):
            return self.array(value)
        if isinstance(value, pd.DataFrame):
            columns = [value.iloc[:, j].to_numpy() for j in range(value.shape[1])]
            return {
                "frame": {
                    "index": self.index(value.index),
                    "columns": self.index(value.columns),
                    "data": [self.array(column) for column in columns],
                }
            }
        if isinstance(value, dict):
            if not all(isinstance(key, str) for key in value):
                raise TypeError("a cache entry holds dicts with string keys only")
            return {"dict": [[key, self.node(item)] for key, item in value.items()]}
        if isinstance(value, list | tuple):
            kind = "list" if isinstance(value, list) else "tuple"
            return {kind: [self.node(item) for item in value]}
        if dataclasses.is_dataclass(value) and _name(type(value)) in VALUE_TYPES:
            fields = {f.name: self.node(getattr(value, f.name)) for f in dataclasses.fields(value)}
            return {"dataclass": _name(type(value)), "fields": fields}
        raise TypeError(f"a cache entry cannot hold a {type(value).__name__}")


def encode(key: str, value: Any) -> tuple[dict, dict[str, np.ndarray]]:
    """The manifest (JSON-able) and the named arrays of ``value`` (module docstring)."""
    encoder = _Encoder()
    tree = encoder.node(value)
    return {"format": FORMAT, "key": key, "value": tree}, encoder.arrays


class _Decoder:
    def __init__(self, arrays: dict[str, np.ndarray]) -> None:
        self.arrays = arrays

    def array(self, node: dict) -> np.ndarray:
        array = self.arrays[node["array"]]
        return array.astype(object) if node["text"] else array

    def index(self, node: dict):
        import pandas as pd

        if "range" in node:
            return pd.RangeIndex(*node["range"], name=node["name"])
        return pd.Index(self.array(node["index"]), name=node["name"])

    def node(self, node: Any) -> Any:
        import pandas as pd

        if node is None or isinstance(node, bool | int | float | str):
            return node
        if not isinstance(node, dict) or len(node) not in (1, 2):
            raise CacheEntryError("unknown node")
        if "array" in node:
            return self.array(node)
        if "frame" in node:
            frame = node["frame"]
            columns = [self.array(item) for item in frame["data"]]
            data = dict(enumerate(columns))
            result = pd.DataFrame(data, index=self.index(frame["index"]))
            result.columns = self.index(frame["columns"])
            return result
        if "dict" in node:
            return {str(key): self.node(item) for key, item in node["dict"]}
        if "list" in node:
            return [self.node(item) for item in node["list"]]
        if "tuple" in node:
            return tuple(self.node(item) for item in node["tuple"])
        if "dataclass" in node:
            if node["dataclass"] not in VALUE_TYPES:
                raise CacheEntryError(f"type {node['dataclass']} is not one a cache entry holds")
            module, _, name = node["dataclass"].partition(":")
            cls = getattr(importlib.import_module(module), name)
            return cls(**{field: self.node(item) for field, item in node["fields"].items()})
        raise CacheEntryError("unknown node")


def write_entry(path: Path, key: str, value: Any) -> None:
    """Save ``value`` under ``key`` as NPZ at ``path`` (the caller renames it into place)."""
    manifest, arrays = encode(key, value)
    text = json.dumps(manifest, allow_nan=True).encode("utf-8")
    with Path(path).open("wb") as stream:
        np.savez(stream, manifest=np.frombuffer(text, dtype=np.uint8), **arrays)


def read_entry(path: Path, key: str) -> Any:
    """The value saved under ``key`` at ``path``, or a :class:`CacheEntryError`."""
    try:
        with np.load(Path(path), allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
        manifest = json.loads(arrays.pop("manifest").tobytes().decode("utf-8"))
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise CacheEntryError("not a cache entry of this format")
        if manifest.get("key") != key:
            raise CacheEntryError("written under another key")
        return _Decoder(arrays).node(manifest["value"])
    except CacheEntryError as error:
        raise CacheEntryError(f"{path}: {error}") from None
    except (OSError, EOFError, ValueError, KeyError, TypeError, IndexError, zipfile.BadZipFile):
        raise CacheEntryError(f"{path}: truncated or damaged") from None
