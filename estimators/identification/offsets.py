"""Static offsets of the suspension pseudo-measurement (Siegloff & Choi eq. 9).

By default :math:`F_{z,i,0}` are the vehicle's static loads, or the measured
corner weights (scale readings, :func:`corner_weight_loads`). With a still
period at the start of a log, the offsets are chosen so that the
pseudo-measurement over that period equals those static loads, which zeroes
the travel sensors at the logged rest position:

.. math:: F_{z,i,0} = F^{static}_{z,i} - z_i(\\bar d, 0)\\,|_{F_0 = 0}

The still-period check asks whether the body *moves*, not whether the
sensors are quiet: the spread of ``ax`` and ``ay`` has the accelerometer's
white noise taken out, :math:`\\sigma_{motion} = \\sqrt{\\max(0, \\sigma^2 -
\\sigma_n^2)}`, with :math:`\\sigma_n` estimated from the data's own
sample-to-sample differences (a robust :math:`\\mathrm{MAD}(\\Delta a) /
(0.6745 \\sqrt 2)`, which body motion sampled at 100 Hz or faster barely
reaches) or given by the user.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.types import Signals
from wheelload.models import (
    GATES,
    GRAVITY,
    INPUTS,
    ModelParameters,
    Vehicle,
    static_loads,
    suspension_function,
)

STILL_SPEED = 0.2  # m/s, largest speed counted as standing still
STILL_MOTION_STD = 0.3  # m/s^2, largest ax/ay motion (noise removed) at rest


@dataclass(frozen=True, kw_only=True)
class StillPeriod:
    """Offsets [N] from a still period and the reason it was accepted, in words."""

    static: np.ndarray
    reason: str


def corner_weight_loads(weights: str | list[float]) -> np.ndarray:
    """Static loads [N] from scale readings ``FL,FR,RL,RR`` [kg]."""
    if isinstance(weights, str):
        parts = [part.strip() for part in weights.split(",")]
        try:
            values = [float(part) for part in parts]
        except ValueError:
            values = []
    else:
        values = [float(w) for w in weights]
    if len(values) != 4 or not all(np.isfinite(values)) or min(values) <= 0.0:
        raise ValueError(
            f"corner weights must be four positive numbers FL,FR,RL,RR in kg, got {weights!r}"
        )
    return np.asarray(values) * GRAVITY


def white_noise_std(values: np.ndarray) -> float:
    """Robust white-noise standard deviation from sample-to-sample differences."""
    steps = np.diff(values[np.isfinite(values)])
    if steps.size < 2:
        return 0.0
    return float(
        order_statistics.median(np.abs(steps - order_statistics.median(steps)))
        / (0.6745 * np.sqrt(2.0))
    )


def check_still_period(
    signals: Signals,
    vehicle: Vehicle,
    duration: float,
    *,
    static: np.ndarray | None = None,
    noise: float | None = None,
) -> StillPeriod:
    """Offsets that make the pseudo-measurement equal ``static`` over the first ``duration`` s.

    ``static`` defaults to the vehicle's static loads; ``noise`` [m/s^2] overrides
    the accelerometer noise estimated from the data. Raises ``ValueError``
    naming the channel if the period is not still.
    """
    if duration <= 0.0:
        raise ValueError(f"still period must be > 0 s, got {duration}")
    if noise is not None and not noise >= 0.0:
        raise ValueError(f"still-period noise must be >= 0 m/s^2, got {noise}")
    window = signals.t <= signals.t[0] + duration
    if window.sum() < 2 or signals.t[-1] < signals.t[0] + duration:
        raise ValueError(f"{signals.source}: log is shorter than the {duration} s still period")
    speed = np.nanmax(np.abs(signals.vx[window]))
    if not speed <= STILL_SPEED:
        raise ValueError(
            f"{signals.source}: channel 'vx' reaches {speed:.3g} m/s in the first {duration} s; "
            "not a still period"
        )
    reasons = []
    for axis, name in ((0, "ax"), (1, "ay")):
        values = signals.acc[window, axis]
        spread = float(np.nanstd(values))
        sensor = white_noise_std(values) if noise is None else noise
        origin = "from its sample differences" if noise is None else "given"
        motion = float(np.sqrt(max(spread**2 - sensor**2, 0.0)))
        if not motion <= STILL_MOTION_STD:
            raise ValueError(
                f"{signals.source}: channel '{name}' varies by {spread:.3g} m/s^2 (1 sigma) in "
                f"the first {duration} s, {motion:.3g} after its noise {sensor:.3g} ({origin}): "
                f"more than {STILL_MOTION_STD} m/s^2, not a still period "
                "(if the car was at rest, give the sensor noise: --still-noise M_S2)"
            )
        reasons.append(
            f"{name} spread {spread:.3g} m/s^2, sensor noise {sensor:.3g} ({origin}), "
            f"motion {motion:.3g} <= {STILL_MOTION_STD}"
        )
    mean_travel = np.nanmean(signals.d[window], axis=0)
    present = signals.travel_present
    if not np.all(np.isfinite(mean_travel[present])):
        raise ValueError(f"{signals.source}: a travel channel has no sample in the still period")
    mean_travel = np.where(present, mean_travel, 0.0)
    unloaded = ModelParameters.from_vehicle(vehicle, np.zeros(4)).vector()
    u = np.zeros(len(INPUTS))
    u[: len(mean_travel)] = mean_travel  # d_fl .. d_rr lead INPUTS; at rest, every term off
    travel_part = np.asarray(suspension_function()(u, np.zeros(len(GATES)), unloaded)).ravel()
    target = static_loads(vehicle) if static is None else np.asarray(static, float)
    reason = f"still period 0-{duration:g} s (speed <= {speed:.2g} m/s; " + "; ".join(reasons) + ")"
    return StillPeriod(static=target - travel_part, reason=reason)


def still_period_static_loads(signals: Signals, vehicle: Vehicle, duration: float) -> np.ndarray:
    """Offsets [N] of :func:`check_still_period` with the vehicle's static loads."""
    return check_still_period(signals, vehicle, duration).static
