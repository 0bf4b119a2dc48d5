"""Channel lags against the log's own physics (``estimators/logs/latency.py``).

Synthetic logs whose relations hold exactly, one channel delayed by a known time:
the lag found must be within 0.01 s of it (the correlation is sampled at 20 Hz and
refined by a parabola; on these band-limited signals the refinement is good to a few
ms), and a log with no delay must show no significant lag. The checks report it.
"""

import numpy as np
import pytest

from wheelload.estimators.logs.checks import Outcome, check_wiring, describe
from wheelload.estimators.logs.latency import channel_lags, cross_lag

RATE = 200.0
DURATION = 60.0
TOLERANCE = 0.01  # s


def _smooth(rng, t, cutoff=0.8):
    """Band-limited random signal (sum of sines below ``cutoff`` Hz), unit scale."""
    frequencies = rng.uniform(0.1, cutoff, 12)
    phases = rng.uniform(0, 2 * np.pi, 12)
    return sum(np.sin(2 * np.pi * f * t + p) for f, p in zip(frequencies, phases)) / 3.0


def _late(t, values, delay):
    """``values`` as logged ``delay`` seconds late: ``y(t) = x(t - delay)``."""
    return np.interp(t - delay, t, values)


def _log(delays, seed=0):
    """vx, ax = dvx/dt, ay = vx wz, travel roll/pitch from the gyro's angles; delays [s]."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(DURATION * RATE)) / RATE
    vx = 25.0 + 3.0 * _smooth(rng, t, 0.3)
    wz = 0.3 * _smooth(rng, t)
    roll, pitch = 0.02 * _smooth(rng, t), 0.01 * _smooth(rng, t)
    rates = np.column_stack([np.gradient(roll, t), np.gradient(pitch, t), wz])
    ax = np.gradient(vx, t)
    ay = vx * wz
    az = 9.81 + 0.3 * _smooth(rng, t)
    track, base = 0.8, 1.3  # m: travel from body angles, compression positive
    side, axle = track * roll / 2, base * pitch / 2
    d = np.column_stack([-side + axle, side + axle, -side - axle, side - axle])
    ax, ay = _late(t, ax, delays.get("ax", 0.0)), _late(t, ay, delays.get("ay", 0.0))
    d = np.column_stack([_late(t, d[:, k], delays.get("d", 0.0)) for k in range(4)])
    return t, vx, np.column_stack([ax, ay, az]), d, rates


def test_cross_lag_finds_a_known_shift():
    rng = np.random.default_rng(3)
    t = np.arange(2000) / 20.0
    p = _smooth(rng, t)
    lag, r, kappa = cross_lag(_late(t, p, 0.33), p, 20.0)
    assert abs(lag - 0.33) < TOLERANCE and r > 0.99 and kappa > 0


@pytest.mark.parametrize("delays", [{"ay": 0.3}, {"ax": 0.15}, {"d": 0.1}, {}])
def test_each_channel_lag_is_found(delays):
    lags = {lag.channel.split()[0]: lag for lag in channel_lags(*_log(delays))}
    for channel in ("ay", "ax", "d"):
        lag = lags[channel]
        assert lag.decided, lag.note
        assert abs(lag.lag - delays.get(channel, 0.0)) < TOLERANCE, (channel, lag)
        assert lag.significant == (channel in delays)
        assert lag.std < 0.01


def test_wiring_checks_name_the_lag_and_the_fix():
    t, vx, acc, d, rates = _log({"ay": 0.3})
    report = check_wiring(t, vx, acc, d, rates)
    (check,) = [c for c in report.checks if c.name == "ay lag against vx wz"]
    assert check.outcome is Outcome.FAILED and abs(check.statistic - 0.3) < TOLERANCE
    assert "add 0.300 to channels.ay.latency" in describe(report)
    assert not report.diagnosis  # a lag is reported, never a reason to refuse the log
    clean = check_wiring(*_log({}))
    assert not [c for c in clean.checks if " lag " in c.name and c.outcome is Outcome.FAILED]


def test_a_straight_line_cannot_decide():
    t, vx, acc, d, rates = _log({})
    rates[:, 2] = 0.0
    acc[:, 1] = 0.0
    vx = np.full_like(vx, 25.0)
    lags = {lag.channel.split()[0]: lag for lag in channel_lags(t, vx, acc, d, rates)}
    assert not lags["ay"].decided and "varies too little" in lags["ay"].note
    assert not lags["ax"].decided
