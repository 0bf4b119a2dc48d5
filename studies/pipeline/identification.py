"""Identify a vehicle file's suspension maps from rig data and drive logs (the fit's settings
from the vehicle file and the command line's choices, the fit, the new file's text).

The least-squares fit is :func:`wheelload.estimators.identification.identify`;
the parameters it may move are the vehicle file's keys, bounded below by the
file's own limits and by the vehicle's plausible range, above by that range.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators.identification import (
    FitLoss,
    FitSettings,
    Identification,
    default_model,
    drive_gates,
    identify,
    piecewise_model,
    read_drive,
    read_rig,
)
from wheelload.estimators.identification.file_keys import (
    lower_bounds,
    parameter_keys,
    plausible_bounds,
)
from wheelload.estimators.identification.model import base_parameter
from wheelload.estimators.identification.report import file_changes
from wheelload.models import ModelParameters, load_vehicle
from wheelload.models.vehicle.file import prepend_comment, set_values


@dataclass(frozen=True, kw_only=True)
class Identified:
    """A vehicle file identified: the fit, the file keys of its parameters, the data sets
    and the new file's text."""

    result: Identification
    keys: dict
    sets: tuple
    text: str


def identify_vehicle(
    vehicle_path: Path,
    *,
    rig: list[str],
    drive: list[str],
    knots: tuple[float, ...] = (),
    loss: FitLoss = FitLoss.LINEAR,
    fixed: frozenset[str] = frozenset(),
    precision: float = 0.25,
    instrumental: bool = False,
    allow_unusual: bool = False,
    channel_map: str | Path | None = None,
    wiring_checks: bool = True,
) -> Identified:
    """Fit the suspension maps of ``vehicle_path`` (a piecewise damper with ``knots``, else
    linear) to the rig files and drive logs; the new file's text carries the changed
    values with an 'identified' comment. ``channel_map`` and ``wiring_checks``: how the
    drive logs are read (:func:`~wheelload.estimators.identification.data.read_drive`)."""
    vehicle = load_vehicle(vehicle_path, allow_unusual=allow_unusual)
    text = vehicle_path.read_text(encoding="utf-8")
    table = tomllib.loads(text)
    model = piecewise_model(knots) if knots else default_model()
    sets = tuple(s for path in rig for s in read_rig(path))
    sets += tuple(
        read_drive(path, model.channel_names(), model.optional,
                   channel_map=channel_map, wiring_checks=wiring_checks)
        for path in drive
    )  # fmt: skip
    # The terms the vehicle file switches on, where the drive logs carry their inputs.
    gates = drive_gates(ModelParameters.from_vehicle(vehicle), sets)
    model = piecewise_model(knots, gates) if knots else default_model(gates)
    keys = parameter_keys(table)
    bounds = lower_bounds(table, keys)
    low, high = plausible_bounds(vehicle)
    bounds |= low
    settings = FitSettings(
        loss=loss,
        fixed=fixed,
        precision=precision,
        lower={
            name: bounds[base_parameter(name)]
            for name in model.parameter_names()
            if base_parameter(name) in bounds
        },
        upper={name: high[name] for name in model.parameter_names() if name in high},
        instrumental=instrumental,
    )
    result = identify(model, sets, ModelParameters.from_vehicle(vehicle), settings)
    changes = file_changes(result, keys)
    header = (
        f"Identified by `wheelload identify` from {vehicle_path.name} with "
        + ", ".join(data.label() for data in sets)
        + f" ({result.loss.value} loss). Changed keys carry an 'identified' comment.\n"
    )
    new_text = prepend_comment(set_values(text, changes), header) if changes else text
    return Identified(result=result, keys=keys, sets=sets, text=new_text)
