"""Named layouts of flat vectors: each entry declared once (name, size, unit, file key).

A :class:`Layout` is an ordered tuple of :class:`Field` entries; every position in the vector
(a slice, an index, a C struct member, a vehicle-file key) is derived from the declaration,
so reordering or resizing an entry moves every use of it together. Works on NumPy arrays and
on CasADi SX/MX vectors alike (values are read by slicing; :meth:`Layout.pack` concatenates).

Example
-------
>>> layout = Layout("noise", (Field("q", unit="N^2/s"), Field("r_c", parts=("v", "p", "r"))))
>>> layout.size, layout.slice("r_c"), layout.names()
(4, slice(1, 4, None), ('q', 'v', 'p', 'r'))
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class Domain:
    """The values an entry may take: finite, within ``[low, high]`` (an end excluded where
    ``open_low`` / ``open_high``); an infinite end is no bound."""

    low: float = -math.inf
    high: float = math.inf
    open_low: bool = False
    open_high: bool = False

    def holds(self, value: float) -> bool:
        """``value`` is finite and within the domain."""
        value = float(value)
        if not math.isfinite(value):
            return False
        above = value > self.low if self.open_low else value >= self.low
        below = value < self.high if self.open_high else value <= self.high
        return above and below

    def describe(self) -> str:
        """The domain as an interval, e.g. ``(0, inf)``."""
        left = "(" if self.open_low or math.isinf(self.low) else "["
        right = ")" if self.open_high or math.isinf(self.high) else "]"
        return f"{left}{self.low:g}, {self.high:g}{right}"


#: Any finite value; a value that is positive; one that is not negative.
FINITE = Domain()
POSITIVE = Domain(0.0, open_low=True)
NON_NEGATIVE = Domain(0.0)


@dataclass(frozen=True)
class Field:
    """One entry of a layout: ``size`` scalars named ``parts`` (default: the field's name
    alone, or ``name_0 ...``); ``file_key`` the vehicle file's key path, if it has one."""

    name: str
    size: int = 0  # 0: len(parts), or 1
    unit: str = ""
    file_key: tuple[str, ...] | None = None
    doc: str = ""
    parts: tuple[str, ...] = field(default=())
    domain: Domain = FINITE  # the values each part may take

    def __post_init__(self) -> None:
        size = self.size or len(self.parts) or 1
        parts = self.parts or ((self.name,) if size == 1 else tuple(
            f"{self.name}_{k}" for k in range(size)))  # fmt: skip
        if len(parts) != size:
            raise ValueError(f"field '{self.name}': {len(parts)} part names for size {size}")
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "parts", tuple(parts))


class Layout:
    """An ordered, named layout of a flat vector (:class:`Field` entries, no gaps)."""

    def __init__(self, name: str, fields: Iterable[Field]) -> None:
        self.name = name
        self.fields = tuple(fields)
        self._slices: dict[str, slice] = {}
        self._index: dict[str, int] = {}
        start = 0
        for f in self.fields:
            if f.name in self._slices:
                raise ValueError(f"layout '{name}': field '{f.name}' declared twice")
            self._slices[f.name] = slice(start, start + f.size)
            for k, part in enumerate(f.parts):
                if part in self._index:
                    raise ValueError(f"layout '{name}': entry '{part}' declared twice")
                self._index[part] = start + k
            start += f.size
        self.size = start

    def __len__(self) -> int:
        return self.size

    def __repr__(self) -> str:
        return f"Layout({self.name!r}, {len(self.fields)} fields, size {self.size})"

    def field(self, name: str) -> Field:
        """The field called ``name``."""
        return self.fields[self.field_names().index(self._known(name))]

    def field_names(self) -> tuple[str, ...]:
        """The fields' names, in order."""
        return tuple(f.name for f in self.fields)

    def names(self) -> tuple[str, ...]:
        """Every scalar entry's name, in vector order (a field's parts)."""
        return tuple(part for f in self.fields for part in f.parts)

    def slice(self, name: str) -> slice:
        """Positions of field ``name``."""
        return self._slices[self._known(name)]

    def span(self, first: str, last: str) -> slice:
        """Positions from field ``first`` through field ``last``."""
        return slice(self.slice(first).start, self.slice(last).stop)

    def index(self, name: str) -> int:
        """Position of scalar entry ``name`` (a part, or a field of size 1)."""
        if name not in self._index:
            raise KeyError(f"layout '{self.name}' has no scalar entry '{name}'")
        return self._index[name]

    def indices(self, names: Iterable[str]) -> list[int]:
        """Positions of scalar entries ``names``."""
        return [self.index(name) for name in names]

    def value(self, vector, name: str):
        """Field or scalar entry ``name`` of ``vector`` (a scalar for a size-1 field)."""
        if name in self._index and (name not in self._slices or self.field(name).size == 1):
            return vector[self._index[name]]
        return vector[self.slice(name)]

    def values(self, vector, names: Iterable[str]):
        """Scalar entries ``names`` of ``vector``, stacked in that order."""
        picked = [self.index(name) for name in names]
        if _casadi(vector, ("SX", "MX", "DM")):
            return ca.vertcat(*[vector[k] for k in picked])
        return np.asarray(vector)[picked]

    def unpack(self, vector) -> dict:
        """``{field name: value}`` of ``vector`` (size-1 fields as scalars)."""
        self._check_size(vector)
        return {f.name: self.value(vector, f.name) for f in self.fields}

    def pack(self, values: Mapping):
        """The vector of ``{field name: value}`` in declaration order (every field, once)."""
        missing = [name for name in self.field_names() if name not in values]
        unknown = [name for name in values if name not in self._slices]
        if missing or unknown:
            raise KeyError(f"layout '{self.name}': missing {missing}, unknown {unknown}")
        pieces = [values[name] for name in self.field_names()]
        if any(_casadi(piece, ("SX", "MX")) for piece in pieces):
            return ca.vertcat(*pieces)
        return np.concatenate([np.ravel(np.asarray(piece, float)) for piece in pieces])

    def replaced(self, vector, values: Mapping):
        """``vector`` with the fields of ``values`` replaced (the rest kept)."""
        return self.pack({**{f.name: vector[self.slice(f.name)] for f in self.fields}, **values})

    def domains(self) -> dict[str, Domain]:
        """``{scalar entry: its field's domain}``, in vector order."""
        return {part: f.domain for f in self.fields for part in f.parts}

    def file_keys(self) -> dict[str, tuple[str, ...]]:
        """``{field name: vehicle-file key}`` of the fields that have one."""
        return {f.name: f.file_key for f in self.fields if f.file_key is not None}

    def subset(self, name: str, fields: Iterable[str]) -> Layout:
        """A layout of some of these fields (their declarations), in the order given."""
        return Layout(name, (self.field(f) for f in fields))

    def _known(self, name: str) -> str:
        if name not in self._slices:
            raise KeyError(f"layout '{self.name}' has no field '{name}'")
        return name

    def _check_size(self, vector) -> None:
        size = vector.numel() if hasattr(vector, "numel") else np.size(vector)
        if size != self.size:
            raise ValueError(f"layout '{self.name}' has {self.size} entries, got {size}")


def _casadi(value, kinds: tuple[str, ...]) -> bool:
    """Whether ``value`` is a CasADi matrix of one of ``kinds``, read from its type's name, so
    that a NumPy caller never loads CasADi (the command line defers it until used)."""
    kind = type(value)
    return kind.__module__.startswith("casadi") and kind.__name__ in kinds
