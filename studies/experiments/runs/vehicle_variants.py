"""Variants of a vehicle file as lists of edits of its text (ablation, mismatch).

A :class:`Variant` is a label and a tuple of :class:`Edit` s; each edit sets
one ``[table] key`` of the file to a number, a list of numbers or a boolean.
The edited text keeps every other line (and comment) of the file; it is
checked by building a :class:`~wheelload.models.vehicle.description.Vehicle` from it.
The studies hash this text, so a variant is cached like any other input.

Example
-------
>>> text = base.read_text()
>>> variant = Variant(label="no ARB", edits=(Edit(table="suspension.front", key="arb_rate",
...     value=0.0), Edit(table="suspension.rear", key="arb_rate", value=0.0)))
>>> edited = variant.apply(text)
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass

from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.models.vehicle.file import replace_values

Value = float | bool | tuple[float, ...]


@dataclass(frozen=True, kw_only=True)
class Edit:
    """Set ``[table] key`` to ``value``."""

    table: str
    key: str
    value: Value

    def text(self) -> str:
        if isinstance(self.value, bool):
            return "true" if self.value else "false"
        if isinstance(self.value, tuple):
            return "[" + ", ".join(f"{v:.9g}" for v in self.value) + "]"
        return f"{self.value:.9g}"


@dataclass(frozen=True, kw_only=True)
class Variant:
    """A labelled set of edits of the study's vehicle file (no edit: the file as it is)."""

    label: str
    edits: tuple[Edit, ...] = ()

    def apply(self, text: str) -> str:
        """``text`` with the edits made; every edited key must exist exactly once."""
        values = {(*edit.table.split("."), edit.key): edit.text() for edit in self.edits}
        try:
            edited = replace_values(text, values)
        except ValueError as error:
            raise ValueError(f"variant '{self.label}': {error}") from None
        vehicle_from_dict(tomllib.loads(edited))  # the variant must be a valid vehicle
        return edited


def value(text: str, table: str, key: str) -> Value:
    """The value of ``[table] key`` in a vehicle file's text (lists as tuples)."""
    node = tomllib.loads(text)
    for part in table.split("."):
        node = node[part]
    found = node[key]
    return tuple(float(v) for v in found) if isinstance(found, list) else found


def scaled(text: str, table: str, key: str, factor: float) -> Edit:
    """An edit that multiplies ``[table] key`` (a number or a list of numbers) by ``factor``."""
    current = value(text, table, key)
    if isinstance(current, tuple):
        return Edit(table=table, key=key, value=tuple(factor * v for v in current))
    return Edit(table=table, key=key, value=factor * float(current))
