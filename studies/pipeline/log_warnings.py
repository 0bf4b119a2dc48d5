"""Warnings a user acts on: each names the channel, what was seen, and what to do.

- a sample rate below :data:`MIN_RATE` (the filter's tuning and validation
  cover 100 Hz - 1 kHz);
- a suspension velocity ``v_*`` that is never negative: a speed magnitude,
  not the signed rate of compression;
- a travel channel ``d_*`` that is flat at zero: a dead or unplugged sensor;
- negative estimated loads: how many samples, how deep, on which wheel, and
  the bounded MHE that keeps :math:`0 \\le F_z`.
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators import Estimate, Signals
from wheelload.models.conventions import WHEELS

MIN_RATE = 100.0  # Hz
UNSIGNED_VELOCITY = 0.05  # m/s, a v_* channel reaching this and never negative is unsigned
FLAT_TRAVEL = 1e-6  # m, a travel channel within this of zero throughout is flat


def signal_warnings(signals: Signals) -> list[str]:
    """Warnings about a log's channels (see module docstring)."""
    travel = [signals.d[:, i][np.isfinite(signals.d[:, i])] for i in range(4)]
    rates = [signals.v[:, i][np.isfinite(signals.v[:, i])] for i in range(4)]
    return channel_warnings(
        signals.source,
        signals.sample_rate,
        travel_count=[f.size for f in travel],
        travel_peak=[float(np.max(np.abs(f))) if f.size else 0.0 for f in travel],
        rate_count=[f.size for f in rates],
        rate_min=[float(f.min()) if f.size else 0.0 for f in rates],
        rate_max=[float(f.max()) if f.size else 0.0 for f in rates],
        velocities_derived=signals.velocities_derived,
    )


def channel_warnings(
    source: str,
    rate: float,
    *,
    travel_count,
    travel_peak,
    rate_count,
    rate_min,
    rate_max,
    velocities_derived: bool,
) -> list[str]:
    """:func:`signal_warnings` from per-wheel statistics of the channels (chunked logs).

    ``travel_count``/``travel_peak``: finite samples of ``d_*`` and their max
    ``|d|``; ``rate_count``/``rate_min``/``rate_max``: of the logged ``v_*``.
    """
    found = []
    if rate < MIN_RATE:
        found.append(
            f"{source}: sample rate {rate:.0f} Hz is below {MIN_RATE:.0f} Hz, the "
            "lowest the filter is tuned and checked for; wheel hop (10-15 Hz) is not resolved "
            "and derived velocities lag: log at 100 Hz or more if you can"
        )
    for i, wheel in enumerate(WHEELS):
        if travel_count[i] and travel_peak[i] <= FLAT_TRAVEL:
            found.append(
                f"{source}: travel channel 'd_{wheel}' is flat at zero for all "
                f"{travel_count[i]} samples: a dead or unplugged sensor? leave it out of the log "
                "or the channel map to run without that corner"
            )
        if velocities_derived:
            continue
        if rate_count[i] and rate_min[i] >= 0.0 and rate_max[i] >= UNSIGNED_VELOCITY:
            found.append(
                f"{source}: velocity channel 'v_{wheel}' is never negative (up to "
                f"{rate_max[i]:.3g} m/s): it looks unsigned; a suspension velocity is "
                "positive in compression and negative in rebound: log it signed, or leave "
                "v_* out to derive it from the travel"
            )
    return found


def load_warnings(estimate: Estimate, source: str) -> list[str]:
    """A warning for negative estimated loads, if there are any."""
    negative = estimate.loads < 0.0
    samples = int(negative.any(axis=1).sum())
    return negative_load_warnings(samples, estimate.loads.min(axis=0), source)


def negative_load_warnings(samples: int, minima: np.ndarray, source: str) -> list[str]:
    """:func:`load_warnings` from the count of samples with a negative load and each
    wheel's minimum (chunked logs)."""
    if samples == 0:
        return []
    wheel = int(np.argmin(minima))
    deepest = float(np.min(minima))
    return [
        f"{source}: {samples} samples with a negative estimated load (down to {deepest:.0f} N "
        f"on {WHEELS[wheel].upper()}): a wheel lifting off, which the Kalman filter does not "
        "bound; the bounded MHE keeps 0 <= Fz (MheSettings(bounded=True), compare with "
        "'wheelload study mhe-vs-kf')"
    ]
