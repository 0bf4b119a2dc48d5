"""The static loads a log is estimated from: measured corner weights, then a still period.

Corner weights (``--corner-weights``, kg) set the static loads; a still period
(``--still-period``) zeroes the travel sensors over the log's first seconds and
checks the car was at rest there (:func:`~wheelload.estimators.check_still_period`).
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators import Signals, check_still_period, corner_weight_loads
from wheelload.models import Vehicle


def static_loads(
    signals: Signals, vehicle: Vehicle, settings
) -> tuple[np.ndarray | None, list[str]]:
    """``(static loads or None, notes)`` of a log's first samples; ``settings`` an
    :class:`~wheelload.studies.pipeline.batch.EstimateSettings`."""
    static, notes = None, []
    if settings.corner_weights is not None:
        static = corner_weight_loads(settings.corner_weights)
        notes.append(f"static loads from corner weights {settings.corner_weights} kg")
    if settings.still_period:
        still = check_still_period(
            signals, vehicle, settings.still_period, static=static, noise=settings.still_noise
        )
        static = still.static
        notes.append(still.reason)
    return static, notes
