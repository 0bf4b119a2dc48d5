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
from wheelload.models.vehicle.file import (
    TABLE,
    add_values,
    assigned_keys,
    replace_values,
    table_key,
)

Value = float | bool | tuple[float, ...]


@dataclass(frozen=True, kw_only=True)
class Edit:
    """Set ``[table] key`` to ``value``."""

    table: str
    key: str
    value: Value
    optional: bool = False  # an optional key: added when the file does not set it

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
        present = assigned_keys(text)
        values, added = {}, []
        for edit in self.edits:
            key = (*edit.table.split("."), edit.key)
            if edit.optional and key not in present:
                added.append(edit)
            else:
                values[key] = edit.text()
        try:
            edited = replace_values(text, values)
            for edit in added:
                edited = _added(edited, edit, self.label)
        except ValueError as error:
            raise ValueError(f"variant '{self.label}': {error}") from None
        vehicle_from_dict(tomllib.loads(edited))  # the variant must be a valid vehicle
        return edited


def _added(text: str, edit: Edit, label: str) -> str:
    """``text`` with the optional key of ``edit`` added: at the end of its table, or under a
    new table header at the end of the file (TOML allows a super-table after its
    sub-tables, e.g. ``[suspension]`` after ``[suspension.front]``)."""
    key = tuple(edit.table.split("."))
    headers = {table_key(match) for line in text.splitlines() if (match := TABLE.match(line))}
    comment = f"variant '{label}'"
    if key in headers:
        return add_values(text, {(*key, edit.key): (edit.value, comment)})
    return text.rstrip("\n") + f"\n\n[{edit.table}]\n{edit.key} = {edit.text()}  # {comment}\n"


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
