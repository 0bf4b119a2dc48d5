"""A plant log re-sampled as a CAN car sends it, and the time-ordered feed it stands for.

:func:`union_frame`: the same frames as one long table in time order, each channel at its
own (jittered) stamps and NaN elsewhere, travel rates and body-rate derivatives left to be
derived: what a channel map with ``[clock] union`` reads.

:func:`can_car_log`: each frame on its own clock (travel and hub accelerometers 100 Hz,
IMU 200 Hz, wheel speed 50 Hz, each with clock jitter), logged its latency after it was
measured (10, 5 and 20 ms), as one long table in order of arrival with NaN where a row has no
value of a channel; some frames arrive out of order (a few rows late) and a few far too late
(older than any rewind allows).

:func:`time_ordered_reference`: the independent computation the rewinding filter must give,
the accepted measurements sorted by time stamp, those of one time stamp merged, the speed
held forward, filtered sample after sample by CasADi's virtual machine
(:meth:`TwoStageKF.reference_step`).
"""

import dataclasses

import numpy as np

from wheelload.estimators import Sample
from wheelload.estimators.guards.settings import guard_settings_for
from wheelload.estimators.kf.rewind import TIMED_INTERVAL_BAND
from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.models import INPUTS
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
)

#: Frames: channels, rate [Hz], latency [s].
FRAMES = {
    "travel": (TRAVEL + TRAVEL_RATE + HUB_ACCELERATION, 100.0, 0.010),
    "imu": (SPECIFIC_FORCE + BODY_RATES + BODY_RATE_DERIVATIVES, 200.0, 0.005),
    "speed": (("vx",), 50.0, 0.020),
}


#: The frames of :func:`union_frame`: the channels of a log, rate [Hz], first stamp [s].
UNION_FRAMES = {
    "travel": (TRAVEL, 100.0, 0.023),
    "imu": (SPECIFIC_FORCE + BODY_RATES, 200.0, 0.02),
    "speed": (("vx",), 50.0, 0.027),
}


def union_frame(signals, duration: float, *, seed: int = 3, jitter: float = 0.2e-3):
    """A DataFrame of the log's channels on the union of their frames' stamps (time order),
    each stamp jittered by up to ``jitter`` [s] (within the 5 % of a 100 Hz travel's
    interval its differentiator allows)."""
    import pandas as pd

    rng = np.random.default_rng(seed)
    t_plant = signals.t - signals.t[0]
    values = dict(zip(INPUTS, input_matrix(signals), strict=True))
    stamps = {}
    for name, (_, rate, first) in UNION_FRAMES.items():
        own = np.arange(first, duration, 1.0 / rate)
        stamps[name] = own + rng.uniform(-jitter / 2, jitter / 2, own.size)  # clock jitter
    t = np.unique(np.concatenate(list(stamps.values())))
    frame = pd.DataFrame({"t": t})
    for name, (channels, _, _) in UNION_FRAMES.items():
        rows = np.searchsorted(t, stamps[name])
        for channel in channels:
            column = np.full(t.size, np.nan)
            column[rows] = np.interp(stamps[name], t_plant, values[channel])
            frame[channel] = column
    return frame


def latencies() -> dict[str, float]:
    """Each frame's channels with its latency [s]."""
    return {channel: delay for channels, _, delay in FRAMES.values() for channel in channels}


def can_car_log(signals, duration: float, *, seed: int = 3, far_late: int = 3):
    """``(t, inputs)``: the rows in order of arrival, ``inputs`` (n, INPUTS) NaN-padded."""
    rng = np.random.default_rng(seed)
    t_plant = signals.t - signals.t[0]
    values = input_matrix(signals)  # (INPUTS, n)
    arrival, rows = [], []
    for channels, rate, delay in FRAMES.values():
        index = [INPUTS.index(c) for c in channels]
        stamps = np.arange(0.02, duration, 1.0 / rate)
        stamps = stamps + rng.uniform(-0.3e-3, 0.3e-3, stamps.size)  # clock jitter
        for stamp in stamps:
            row = np.full(len(INPUTS), np.nan)
            row[index] = [np.interp(stamp, t_plant, values[i]) for i in index]
            arrival.append(stamp + delay)
            rows.append(row)
    arrival, rows = np.array(arrival), np.array(rows)
    order = list(np.argsort(arrival, kind="stable"))
    # Out of order: one frame in 25 arrives two to six rows later than its turn.
    for k in range(10, len(order) - 10, 25):
        order.insert(k + int(rng.integers(2, 7)), order.pop(k))
    # Far too late: a few frames arrive after everything 0.6 s younger.
    for k in np.linspace(len(order) * 0.3, len(order) * 0.8, far_late).astype(int):
        order.insert(min(k + 250, len(order)), order.pop(k))
    logged = arrival[order]  # a frame arriving late carries its own (early) logged time
    return logged, rows[order]


def time_ordered_reference(kf: TwoStageKF, stamps, channels, accepted, *, speed_hold,
                           first_interval):  # fmt: skip
    """Loads (m, 4) and the sorted unique stamps (m,) of the accepted measurements, filtered
    in time order by ``kf``'s reference step (a filter of its own with the timed filter's
    tuning: ``interval_band`` at its largest)."""
    guards = dataclasses.replace(guard_settings_for(kf.vehicle), interval_band=TIMED_INTERVAL_BAND)
    nominal = kf.sample_interval or float(TUNING.value(kf.tuning, "sample_interval"))
    reference = TwoStageKF(kf.vehicle, guard_settings=guards, sample_interval=nominal,
                           check_file=False)  # fmt: skip
    stamps, channels = stamps[accepted], channels[accepted]
    order = np.argsort(stamps, kind="stable")
    unique, merged = [], []
    for k in order:
        if unique and unique[-1] == stamps[k]:
            present = np.isfinite(channels[k])
            merged[-1][present] = channels[k][present]
        else:
            unique.append(stamps[k])
            merged.append(channels[k].copy())
    speed = INPUTS.index("vx")
    held, held_at = np.nan, np.nan
    state, loads, time = reference.initial_state(), [], None
    for t, u in zip(unique, merged):
        if np.isfinite(u[speed]):
            held, held_at = u[speed], t
        elif t - held_at <= speed_hold:
            u[speed] = held
        sample = Sample(d=u[0:4], v=u[4:8], acc=u[8:11], vx=u[11], rates=u[12:15],
                        rate_dots=u[15:18], hub=u[18:22])  # fmt: skip
        dt = first_interval if time is None else t - time
        state, _ = reference.reference_step(state, sample, dt)
        loads.append(state.x)
        time = t
    return np.array(loads), np.array(unique)
