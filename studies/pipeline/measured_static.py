"""The static loads a log is estimated from, as measured: corner weights, then a still period.

Corner weights (``--corner-weights``, kg) set the static loads; a still period
(``--still-period``) zeroes the travel sensors over the log's first seconds and
checks the car was at rest there (:func:`~wheelload.estimators.check_still_period`).
``settings`` is an :class:`~wheelload.studies.pipeline.batch.EstimateSettings`.
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators import Signals, check_still_period, corner_weight_loads
from wheelload.models import Vehicle


def measured_static_loads(
    signals: Signals, vehicle: Vehicle, settings
) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads or None, notes)``: :func:`corner_weights`, then :func:`still_period`
    on the log's first samples."""
    static, notes = corner_weights(settings)
    static, still = still_period(signals, vehicle, settings, static)
    return static, notes + still


def corner_weights(settings) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads or None, notes)`` from the measured corner weights, if given."""
    if settings.corner_weights is None:
        return None, []
    static = corner_weight_loads(settings.corner_weights)
    return static, [f"static loads from corner weights {settings.corner_weights} kg"]


def still_period(
    signals: Signals, vehicle: Vehicle, settings, static: np.ndarray | None
) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads, notes)`` after the still-period check, if a period is given."""
    if not settings.still_period:
        return static, []
    still = check_still_period(
        signals, vehicle, settings.still_period, static=static, noise=settings.still_noise
    )
    return still.static, [still.reason]
