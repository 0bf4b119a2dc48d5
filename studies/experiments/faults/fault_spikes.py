"""Isolation table: one single-sample spike on each input channel, and what the monitor did.

One spike in the middle of a clean plant log, on one channel at a time (travel
+10 mm, travel rate +1 m/s, specific force +15 m/s^2, speed +20 m/s, body rate
+1 rad/s). The fault monitor may isolate the spiked channel or none, never a
healthy one (issue 21, item 7). Scores per channel: the channels isolated,
for how long [s], and the change of the pooled RMSE against the plant's
reference loads (guarded filter, spiked log minus clean log) [N].

Command: ``wheelload bench faults --spikes`` (with ``--vehicle``, ``--model``).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from wheelload.estimators import Estimator, Signals
from wheelload.models.inputs import SPECIFIC_FORCE, TRAVEL, TRAVEL_RATE

#: Logs of the table: the car at rest and a lane change.
SPIKE_SCENARIOS = ("standstill", "iso-dlc")
#: Channels spiked, each with (Signals field, column, size in SI units).
RATES = ("wx", "wy", "wz")
SPIKE_CHANNELS = {
    **{name: ("d", i, 0.010) for i, name in enumerate(TRAVEL)},
    **{name: ("v", i, 1.0) for i, name in enumerate(TRAVEL_RATE)},
    **{name: ("acc", i, 15.0) for i, name in enumerate(SPECIFIC_FORCE)},
    "vx": ("vx", None, 20.0),
    **{name: ("rates", i, 1.0) for i, name in enumerate(RATES)},
}


def spiked(signals: Signals, channel: str, row: int) -> Signals:
    """``signals`` with one spike on ``channel`` at sample ``row`` (a copy)."""
    field, column, size = SPIKE_CHANNELS[channel]
    values = getattr(signals, field)
    if values is None:
        raise ValueError(f"spike on {channel}: the log has no {field} channel")
    values = np.array(values, float)
    if column is None:
        values[row] += size
    else:
        values[row, column] += size
    return dataclasses.replace(signals, **{field: values})


def isolated_seconds(faults: pd.DataFrame, interval: float) -> float:
    """Total time [s] the records of ``faults`` cover (each record ends on its last sample)."""
    return float((faults["end"] - faults["start"] + interval).sum()) if len(faults) else 0.0


def spike_table(kf: Estimator, signals: Signals, scenario: str, rmse) -> pd.DataFrame:
    """One row per channel of :data:`SPIKE_CHANNELS` spiked once at mid-log.

    ``rmse(loads, reference) -> float`` is the pooled RMSE; ``healthy_isolated`` names
    every other channel the monitor isolated ("-": none).
    """
    clean = rmse(kf.run(signals).loads, signals.reference)
    interval = float(np.median(np.diff(signals.t)))
    row = len(signals) // 2
    rows = []
    for channel in SPIKE_CHANNELS:
        estimate = kf.run(spiked(signals, channel, row))
        faults = estimate.faults
        names = sorted(set(faults["channel"]))
        healthy = [name for name in names if name != channel]
        rows.append(
            {
                "vehicle": kf.vehicle.name,
                "scenario": scenario,
                "channel": channel,
                "isolated": ",".join(names) or "-",
                "isolated_s": isolated_seconds(faults, interval),
                "healthy_isolated": ",".join(healthy) or "-",
                "rmse_change": rmse(estimate.loads, signals.reference) - clean,
            }
        )
    return pd.DataFrame(rows)
