"""The online payload filter's settings in the tuning vector (``estimators/kf/payload.py``).

Kept apart from the filter's symbolic update, so that the tuning vector is made
without the models.
"""

from __future__ import annotations

import numpy as np

from wheelload.models import Vehicle

#: The payload filter's entries of the tuning vector, in order.
PAYLOAD_TUNING = (
    "payload_estimate",
    "payload_mass_std",
    "payload_position_std_x",
    "payload_position_std_y",
    "payload_position_std_z",
    "payload_residual_density_vertical",
    "payload_residual_density_pitch",
    "payload_residual_density_roll",
    "payload_drift_density",
    "payload_standstill_density",
    "payload_standstill_speed",
    "payload_gate",
    "payload_acceleration_scale_vertical",
    "payload_acceleration_scale_pitch",
    "payload_acceleration_scale_roll",
)


def payload_tuning(vehicle: Vehicle) -> np.ndarray:
    """The vehicle file's ``[filter.payload]`` in :data:`PAYLOAD_TUNING` order.

    Estimation is off where the file says travel is zeroed at the start of a log.
    """
    t = vehicle.filter.payload
    on = t.estimate and t.travel_from_reference
    return np.array(
        [
            float(on),
            t.mass_std,
            *t.position_std,
            *t.residual_density,
            t.drift_density,
            t.standstill_density,
            t.standstill_speed,
            t.gate,
            *t.acceleration_scale,
        ]  # fmt: skip
    )
