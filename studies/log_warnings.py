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

MIN_RATE = 100.0  # Hz
UNSIGNED_VELOCITY = 0.05  # m/s, a v_* channel reaching this and never negative is unsigned
FLAT_TRAVEL = 1e-6  # m, a travel channel within this of zero throughout is flat
WHEELS = ("fl", "fr", "rl", "rr")


def signal_warnings(signals: Signals) -> list[str]:
    """Warnings about a log's channels (see module docstring)."""
    found = []
    rate = signals.sample_rate
    if rate < MIN_RATE:
        found.append(
            f"{signals.source}: sample rate {rate:.0f} Hz is below {MIN_RATE:.0f} Hz, the "
            "lowest the filter is tuned and checked for; wheel hop (10-15 Hz) is not resolved "
            "and derived velocities lag: log at 100 Hz or more if you can"
        )
    for i, wheel in enumerate(WHEELS):
        travel = signals.d[:, i]
        finite = travel[np.isfinite(travel)]
        if finite.size and np.all(np.abs(finite) <= FLAT_TRAVEL):
            found.append(
                f"{signals.source}: travel channel 'd_{wheel}' is flat at zero for all "
                f"{finite.size} samples: a dead or unplugged sensor? leave it out of the log "
                "or the channel map to run without that corner"
            )
        if signals.velocities_derived:
            continue
        rate_values = signals.v[:, i]
        finite = rate_values[np.isfinite(rate_values)]
        if finite.size and finite.min() >= 0.0 and finite.max() >= UNSIGNED_VELOCITY:
            found.append(
                f"{signals.source}: velocity channel 'v_{wheel}' is never negative (up to "
                f"{finite.max():.3g} m/s): it looks unsigned; a suspension velocity is "
                "positive in compression and negative in rebound: log it signed, or leave "
                "v_* out to derive it from the travel"
            )
    return found


def load_warnings(estimate: Estimate, source: str) -> list[str]:
    """A warning for negative estimated loads, if there are any."""
    negative = estimate.loads < 0.0
    if not negative.any():
        return []
    samples = int(negative.any(axis=1).sum())
    wheel = int(np.argmin(estimate.loads.min(axis=0)))
    deepest = float(estimate.loads.min())
    return [
        f"{source}: {samples} samples with a negative estimated load (down to {deepest:.0f} N "
        f"on {WHEELS[wheel].upper()}): a wheel lifting off, which the Kalman filter does not "
        "bound; the bounded MHE keeps 0 <= Fz (MheSettings(bounded=True), compare with "
        "'wheelload study mhe-vs-kf')"
    ]
