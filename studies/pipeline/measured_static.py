"""The static loads a log is estimated from, as measured: corner weights, then a still period.

Corner weights (``--corner-weights``, kg) set the static loads; a still period
(``--still-period``) zeroes the travel sensors over the log's first seconds and
checks the car was at rest there
(:func:`~wheelload.estimators.identification.offsets.check_still_period`).
``settings`` is an :class:`~wheelload.studies.pipeline.batch.EstimateSettings`.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from wheelload.models import GRAVITY, Vehicle

if TYPE_CHECKING:
    from wheelload.estimators import Signals

PAYLOAD_INVISIBLE = (
    "a payload is invisible to the springs, so mass and CG are not estimated online: "
    "give measured corner weights (--corner-weights) or the loaded masses in the file"
)


def measured_static_loads(
    signals: Signals, vehicle: Vehicle, settings
) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads or None, notes)``: :func:`corner_weights`, then :func:`still_period`
    on the log's first samples."""
    static, notes = corner_weights(settings)
    if static is not None and not np.isfinite(signals.d).any():
        notes = [without_travel(static, vehicle)]
    static, still = still_period(signals, vehicle, settings, static)
    return static, notes + still


def without_travel(static: np.ndarray, vehicle: Vehicle) -> str:
    """What corner weights do for a log without travel sensors: they set the suspension
    rows' static loads, which such a log never runs; their total still weighs the car."""
    measured = float(np.sum(static)) / GRAVITY
    return (
        f"corner weights {measured:.1f} kg in all against the file's {vehicle.mass.total:.1f} "
        "kg; they set the static loads of the suspension rows, which this log without travel "
        "sensors never runs, so they hardly change its loads: put the measured mass and CG "
        "in the vehicle file (wheelload weigh gives them from logs at rest)"
    )


def corner_weights(settings) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads or None, notes)`` from the measured corner weights, if given."""
    if settings.corner_weights is None:
        return None, []
    from wheelload.estimators.identification.offsets import corner_weight_loads

    static = corner_weight_loads(settings.corner_weights)
    return static, [f"static loads from corner weights {settings.corner_weights} kg"]


def still_period(
    signals: Signals, vehicle: Vehicle, settings, static: np.ndarray | None
) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads, notes)`` after the still-period check, if a period is given."""
    if not settings.still_period:
        return static, []
    from wheelload.estimators.identification.offsets import check_still_period

    still = check_still_period(
        signals, vehicle, settings.still_period, static=static, noise=settings.still_noise
    )
    return still.static, [still.reason]


def payload_reference(vehicle: Vehicle, settings) -> tuple[Vehicle, list[str]]:
    """``(vehicle, notes)``: online mass and CG need travel measured from the file's
    reference state; a still period zeroes it at the log's start instead, so it turns the
    estimation off, and a file that says its travel is zeroed is told."""
    payload = vehicle.filter.payload
    if settings.still_period and payload.travel_from_reference:
        return with_travel_zeroed(vehicle), [
            f"travel zeroed over the still period: {PAYLOAD_INVISIBLE}"
        ]
    if not payload.travel_from_reference:
        return vehicle, [
            "travel zeroed at the log's start ([filter.payload] travel_from_reference = "
            f"false): {PAYLOAD_INVISIBLE}"
        ]
    return vehicle, []


def with_travel_zeroed(vehicle: Vehicle) -> Vehicle:
    """``vehicle`` whose travel reads 0 at the log's start ([filter.payload]
    travel_from_reference = false), so no payload is estimated."""
    payload = dataclasses.replace(vehicle.filter.payload, travel_from_reference=False)
    return vehicle.replace(filter=dataclasses.replace(vehicle.filter, payload=payload))
