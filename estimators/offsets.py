"""Static offsets of the suspension pseudo-measurement (Siegloff & Choi eq. 9).

By default :math:`F_{z,i,0}` are the vehicle's static loads. With a still
period at the start of a log, the offsets are chosen so that the
pseudo-measurement over that period equals the static loads, which zeroes the
travel sensors at the logged rest position:

.. math:: F_{z,i,0} = F^{static}_{z,i} - z_i(\\bar d, 0)\\,|_{F_0 = 0}
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.signals import Signals
from wheelload.models import (
    GATES,
    INPUTS,
    ModelParameters,
    Vehicle,
    static_loads,
    suspension_function,
)

STILL_SPEED = 0.2  # m/s, largest speed counted as standing still
STILL_ACCELERATION_STD = 0.3  # m/s^2, largest ax/ay standard deviation at rest


def still_period_static_loads(signals: Signals, vehicle: Vehicle, duration: float) -> np.ndarray:
    """Offsets [N] that make the pseudo-measurement equal the static loads at rest.

    Raises ``ValueError`` naming the channel if the first ``duration`` seconds
    are not a still period.
    """
    if duration <= 0.0:
        raise ValueError(f"still period must be > 0 s, got {duration}")
    window = signals.t <= signals.t[0] + duration
    if window.sum() < 2 or signals.t[-1] < signals.t[0] + duration:
        raise ValueError(f"{signals.source}: log is shorter than the {duration} s still period")
    speed = np.nanmax(np.abs(signals.vx[window]))
    if not speed <= STILL_SPEED:
        raise ValueError(
            f"{signals.source}: channel 'vx' reaches {speed:.3g} m/s in the first {duration} s; "
            "not a still period"
        )
    for axis, name in ((0, "ax"), (1, "ay")):
        spread = np.nanstd(signals.acc[window, axis])
        if not spread <= STILL_ACCELERATION_STD:
            raise ValueError(
                f"{signals.source}: channel '{name}' varies by {spread:.3g} m/s^2 (1 sigma) "
                f"in the first {duration} s; not a still period"
            )
    mean_travel = np.nanmean(signals.d[window], axis=0)
    if not np.all(np.isfinite(mean_travel)):
        raise ValueError(f"{signals.source}: a travel channel has no sample in the still period")
    unloaded = ModelParameters.from_vehicle(vehicle, np.zeros(4)).vector()
    u = np.zeros(len(INPUTS))
    u[: len(mean_travel)] = mean_travel  # d_fl .. d_rr lead INPUTS; at rest, every term off
    travel_part = np.asarray(suspension_function()(u, np.zeros(len(GATES)), unloaded)).ravel()
    return static_loads(vehicle) - travel_part
