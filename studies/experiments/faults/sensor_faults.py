"""Sensor faults injected into a log: stuck, drifting and spiking travel sensors, biases.

Each fault starts at ``onset`` (a fraction of the log) and lasts to its end;
the reference loads are untouched, so an estimator's error on the faulted
log measures what the fault costs it.

Example
-------
>>> faulty = inject(read_log("iso-dlc.parquet"), Fault.STUCK)
"""

from __future__ import annotations

import dataclasses

import numpy as np

from wheelload.estimators import Signals
from wheelload.studies.experiments.runs.choices import Fault

DRIFT_RATE = 0.001  # m/s
SPIKE = 0.02  # m
SPIKE_SHARE = 0.01
AY_BIAS = 0.5  # m/s^2
OFFSET = 0.004  # m


def inject(signals: Signals, fault: Fault, *, onset: float = 0.2, seed: int = 0) -> Signals:
    """``signals`` with ``fault`` from ``onset`` (fraction of the samples) to the end."""
    d, v, acc = signals.d.copy(), signals.v.copy(), signals.acc.copy()
    n = len(signals)
    start = int(onset * n)
    rest = slice(start, n)
    if fault is Fault.STUCK:
        d[rest, 0] = d[start, 0]
        v[rest, 0] = 0.0
    elif fault is Fault.DRIFT:
        d[rest, 0] += DRIFT_RATE * (signals.t[rest] - signals.t[start])
        v[rest, 0] += DRIFT_RATE
    elif fault is Fault.SPIKES:
        rng = np.random.default_rng(seed)
        rows = rng.choice(n, size=max(1, int(SPIKE_SHARE * n)), replace=False)
        corners = rng.integers(0, 4, size=rows.size)
        d[rows, corners] += SPIKE * rng.choice([-1.0, 1.0], size=rows.size)
    elif fault is Fault.ACCELERATION_BIAS:
        acc[rest, 1] += AY_BIAS
    elif fault is Fault.TRAVEL_OFFSET:
        d[:, :2] += OFFSET
    return dataclasses.replace(signals, d=d, v=v, acc=acc)
