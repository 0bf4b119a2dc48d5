"""Channels on their own clocks (``[clock] union``): each travel's rate derived on its own
stamps, the checks on the IMU's stamps, the speed on every row.

The table is a smooth synthetic drive sent as three frames with their own clocks and
jitter: travel 100 Hz, IMU 200 Hz, speed 50 Hz. Tolerances: a channel's rate on its own
stamps is the differentiator run on that channel alone, to the bit; against the analytic
derivative of the travel the first-order filter (20 Hz corner, Tustin at 100 Hz) lags a
1.5 Hz wave by about f/f_c = 0.075 rad, so 10 % of the peak rate.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import LogError
from wheelload.estimators.logs.checks import check_wiring
from wheelload.estimators.logs.signals import derive_velocities, signals_from_frame
from wheelload.estimators.types import TRAVEL

DURATION = 12.0
FREQUENCY = 1.5  # Hz, the travel wave
AMPLITUDE = 0.01  # m
FRAMES = {"travel": (100.0, 0.003), "imu": (200.0, 0.0), "speed": (50.0, 0.0071)}  # Hz, offset


def _stamps(rate, offset, jitter, rng):
    stamps = offset + np.arange(int(DURATION * rate)) / rate
    return stamps + rng.uniform(0.0, jitter, stamps.size)


def _union_table(jitter: float, seed: int = 1) -> pd.DataFrame:
    """The three frames' samples on the union of their stamps, NaN where a frame is absent."""
    rng = np.random.default_rng(seed)
    stamps = {name: _stamps(rate, offset, jitter, rng) for name, (rate, offset) in FRAMES.items()}
    t = np.unique(np.concatenate(list(stamps.values())))
    frame = pd.DataFrame({"t": t})
    speed = lambda s: 15.0 + 5.0 * np.sin(0.3 * s)  # noqa: E731
    columns = {
        "travel": {f"d_{w}": (lambda s, k=k: AMPLITUDE * np.sin(2 * np.pi * FREQUENCY * s + k))
                   for k, w in enumerate(("fl", "fr", "rl", "rr"))},
        "imu": {"ax": lambda s: 1.5 * np.cos(0.3 * s),  # d(vx)/dt
                "ay": lambda s: speed(s) * 0.1 * np.sin(0.4 * s),  # vx wz
                "az": lambda s: np.full(s.shape, 9.81), "wz": lambda s: 0.1 * np.sin(0.4 * s)},
        "speed": {"vx": speed},
    }  # fmt: skip
    for name, functions in columns.items():
        rows = np.searchsorted(t, stamps[name])
        for column, function in functions.items():
            values = np.full(t.size, np.nan)
            values[rows] = function(stamps[name])
            frame[column] = values
    return frame


@pytest.mark.parametrize("jitter", [0.0, 200e-6])
def test_each_travel_rate_is_derived_on_its_own_stamps(jitter):
    """The rate of each travel on its own rows is that of the travel alone, to the bit."""
    frame = _union_table(jitter)
    signals = signals_from_frame(frame, wiring_checks=False, own_clocks=True)
    rows = np.flatnonzero(frame["d_fl"].notna())
    alone = derive_velocities(frame["t"].to_numpy()[rows], frame[list(TRAVEL)].to_numpy()[rows])
    np.testing.assert_array_equal(signals.v[rows], alone)
    assert np.all(np.isnan(np.delete(signals.v, rows, axis=0)))
    t = frame["t"].to_numpy()[rows]
    exact = AMPLITUDE * 2 * np.pi * FREQUENCY * np.cos(2 * np.pi * FREQUENCY * t)
    settled = t > 1.0
    peak = AMPLITUDE * 2 * np.pi * FREQUENCY
    assert np.max(np.abs(signals.v[rows, 0] - exact)[settled]) < 0.1 * peak


@pytest.mark.parametrize("jitter", [0.0, 200e-6])
def test_the_union_clock_alone_is_refused(jitter):
    """What ``own_clocks`` replaces: the differentiator on the union of the frames' stamps,
    uneven however steady each frame's clock is."""
    with pytest.raises(LogError, match="not uniform enough"):
        signals_from_frame(_union_table(jitter), wiring_checks=False)


def test_speed_is_interpolated_onto_every_row_and_the_checks_run_on_the_imu_stamps():
    frame = _union_table(200e-6)
    signals = signals_from_frame(frame, wiring_checks=False, own_clocks=True)
    assert signals.own_clocks
    inside = (signals.t >= frame["t"][frame["vx"].notna()].iloc[0]) & (
        signals.t <= frame["t"][frame["vx"].notna()].iloc[-1]
    )
    assert np.all(np.isfinite(signals.vx[inside]))
    expected = 15.0 + 5.0 * np.sin(0.3 * signals.t[inside])
    # linear interpolation: within h^2/8 max|f''| (steps h up to 21 ms)
    assert np.max(np.abs(signals.vx[inside] - expected)) < 5.0 * 0.3**2 / 8 * 0.021**2
    report = check_wiring(signals.t, signals.vx, signals.acc, signals.d, signals.rates,
                          own_clocks=True)  # fmt: skip
    lateral = [c for c in report.checks if c.name == "vx wz against ay"]
    assert lateral and lateral[0].statistic > 0.99  # ay = vx wz, compared on the IMU's rows
