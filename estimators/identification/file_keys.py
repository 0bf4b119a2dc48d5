"""Where each model parameter lives in the vehicle file, and its bounds, found from the file.

A key maps to a model parameter when changing the key by ``delta`` changes
exactly one parameter by the same ``delta`` (parameters derived from it may
move too) (``ModelParameters.from_vehicle``
decides; nothing is listed by hand). A parameter's lower bound is 0 when the
vehicle file's own validation rejects a negative value for its key.

Example
-------
>>> keys = parameter_keys(tomllib.loads(path.read_text()))
>>> keys["spring_front"]
('suspension', 'front', 'spring_rate')
"""

from __future__ import annotations

import copy
from collections.abc import Iterator

import numpy as np

from wheelload.models import ModelParameters, Vehicle, VehicleFileError, vehicle_from_dict
from wheelload.models.vehicle.plausibility import RANGES

Key = tuple[str, ...]
SKIPPED_SECTIONS = ("plant", "filter")  # never model parameters of the suspension or equilibrium


def _numeric_keys(table: dict, prefix: Key = ()) -> Iterator[Key]:
    for name, value in table.items():
        key = (*prefix, name)
        if isinstance(value, dict):
            if not prefix and name in SKIPPED_SECTIONS:
                continue
            yield from _numeric_keys(value, key)
        elif isinstance(value, int | float) and not isinstance(value, bool):
            yield key


def _get(table: dict, key: Key):
    for part in key:
        table = table[part]
    return table


def _with(table: dict, key: Key, value: float) -> dict:
    changed = copy.deepcopy(table)
    inner = changed
    for part in key[:-1]:
        inner = inner[part]
    inner[key[-1]] = value
    return changed


def parameter_keys(table: dict) -> dict[str, Key]:
    """Model parameter name -> vehicle-file key path, for every one-to-one parameter."""
    base = ModelParameters.from_vehicle(vehicle_from_dict(table)).vector()
    names = ModelParameters.names()
    keys: dict[str, Key] = {}
    for key in _numeric_keys(table):
        value = float(_get(table, key))
        delta = 1e-3 * max(abs(value), 1.0)
        try:
            moved = ModelParameters.from_vehicle(
                vehicle_from_dict(_with(table, key, value + delta))
            ).vector()
        except VehicleFileError:
            continue
        # Derived parameters (e.g. a default computed from the rates) may move too.
        matched = np.flatnonzero(np.isclose(moved - base, delta, rtol=1e-9, atol=0.0))
        if matched.size == 1:
            keys[names[matched[0]]] = key
    return keys


def lower_bounds(table: dict, keys: dict[str, Key]) -> dict[str, float]:
    """0 for each parameter whose file key must not be negative, by the file's validation."""
    bounds = {}
    for name, key in keys.items():
        try:
            vehicle_from_dict(_with(table, key, -1.0 - abs(float(_get(table, key)))))
        except VehicleFileError:
            bounds[name] = 0.0
    return bounds


def key_text(key: Key) -> str:
    return ".".join(key)


#: Model parameters that are a share of a vehicle-file key (no one-to-one key, so
#: :func:`parameter_keys` skips them): parameter -> (key in ``plausibility.RANGES``, share).
SHARED_KEYS = {
    "unsprung_front": ("mass.unsprung_front", 0.5),  # one corner of the axle's mass
    "unsprung_rear": ("mass.unsprung_rear", 0.5),
}


def plausible_bounds(vehicle: Vehicle) -> tuple[dict[str, float], dict[str, float]]:
    """Lower and upper bounds of :data:`SHARED_KEYS` from the physical ranges of their keys
    (``wheelload.models.vehicle.plausibility``): e.g. an unsprung corner mass between 1 % and
    12.5 % of the total mass, never negative."""
    lower, upper = {}, {}
    for name, (key, share) in SHARED_KEYS.items():
        accepted = RANGES[key](vehicle)
        lower[name] = max(0.0, share * accepted.low)
        upper[name] = share * accepted.high
    return lower, upper
