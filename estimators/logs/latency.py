r"""Per-channel lag against the physics the log already holds (cross-correlation).

A channel logged late (a CAN gateway, a filter inside a sensor) is found by
the lag :math:`\tau` that best aligns it with what other channels predict of it:

- ``ay`` against :math:`v_x \omega_z` (steady cornering; the lateral-velocity rate
  :math:`\dot v_y`, not logged, is small against it at the body's low frequencies);
- ``ax`` against :math:`\dot v_x` (level ground);
- the travels' roll, :math:`(d_{fr} + d_{rr} - d_{fl} - d_{rl})/2`, against the roll
  angle integrated from ``wx``, and their pitch, :math:`(d_{fl} + d_{fr} - d_{rl} -
  d_{rr})/2`, against the pitch angle from ``wy``: kinematics, no dynamics between.

Both sides are put on a uniform grid, band-passed (zero phase, :data:`BANDS`) and
decimated to :data:`RATE`; the normalised cross-correlation :math:`r(\tau)` is taken over
:math:`|\tau| \le` :data:`MAX_LAG` and its peak refined by a parabola through the three
best lags. :math:`\tau > 0`:
the channel lags its prediction (shift its time stamps back by :math:`\tau`, the
channel map's ``latency`` key). Confidence: the peak correlation :math:`r` and the
standard error of the peak lag (Carter 1987, time-delay estimation),

.. math:: \sigma_\tau^2 = \frac{1 - r^2}{r^2 \, N \, \kappa},
   \qquad N = 2 B T, \quad \kappa = -\ddot r(\tau^*) / r(\tau^*),

with :math:`N` independent samples in the band :math:`B` over :math:`T` seconds and
:math:`\kappa` the peak's curvature. A lag is decided when :math:`|r| \ge`
:data:`MIN_CORRELATION`, :math:`\sigma_\tau \le` :data:`MAX_STD`, the predicting
side varies (:data:`MIN_STD`) and a lag beyond :data:`LAG_TOLERANCE` explains most of the
misfit (:data:`MIN_MISFIT_RATIO`). On the plant's logs an ``ay`` delay is found from
0.06 s on the lane change, from 0.3 s (not 0.1 s) on the brake in a turn, and not on the
banked chicane, whose bank changes the relation itself; the omitted lateral-velocity rate
biases the ``ay`` lag by +0.01 to +0.02 s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kernels import order_statistics, zero_phase
from wheelload.models.conventions import WHEELS

#: Hz, the band of each relation: the body's quasi-static response for the accelerations;
#: for the travels, above the road's grade and bank changes (which the gyro sees and the
#: travel does not) and below wheel hop.
BANDS = {"ay": (0.05, 2.0), "ax": (0.05, 2.0), "roll": (0.5, 3.0), "pitch": (0.5, 3.0)}
RATE = 20.0  # Hz after band-pass and decimation
MAX_LAG = 1.0  # s
MIN_CORRELATION = 0.9
#: Least ratio of the misfit without and with the lag, (1 - r(0)^2) / (1 - r^2), for a lag
#: beyond :data:`LAG_TOLERANCE` to be decided: the lag must explain most of the misfit.
#: A bank or a grade changes the relation itself (ay holds g sin(bank)); on the plant's
#: chicanes a lag explains 5-11x, a true 0.3 s delay of ay on the lane change 370x.
MIN_MISFIT_RATIO = 20.0
MAX_STD = 0.05  # s, largest standard error of a decided lag
#: Smallest standard deviation of the band-passed prediction to decide [its unit].
MIN_STD = {"ay": 0.3, "ax": 0.3, "roll": 0.002, "pitch": 0.001}  # m/s^2, m/s^2, rad, rad
#: A decided lag within this of zero (or within 2 sigma) is no lag [s]: the omitted lateral-
#: velocity rate alone shifts ay by about 0.02 s on a lane change.
LAG_TOLERANCE = 0.03


@dataclass(frozen=True, kw_only=True)
class Lag:
    """The lag of one channel against its prediction from other channels."""

    channel: str  # ay, ax, d (travel)
    against: str  # the prediction, in words
    lag: float  # s, > 0: the channel lags
    std: float  # s, standard error
    correlation: float  # normalised cross-correlation at the peak
    decided: bool
    note: str  # why not decided, or ""

    @property
    def significant(self) -> bool:
        """A decided lag larger than :data:`LAG_TOLERANCE` and two standard errors."""
        return self.decided and abs(self.lag) > max(LAG_TOLERANCE, 2.0 * self.std)


def _uniform(t: np.ndarray, values: np.ndarray, grid: np.ndarray) -> np.ndarray | None:
    """``values`` interpolated onto ``grid`` over its finite samples; None if too few."""
    good = np.isfinite(t) & np.isfinite(values)
    if good.sum() < 0.5 * grid.size:
        return None
    return np.interp(grid, t[good], values[good])


def _band(values: np.ndarray, fs: float, band: tuple[float, float]) -> np.ndarray:
    """Zero-phase band-pass ``band`` [Hz], decimated to :data:`RATE`."""
    b, a = zero_phase.butter2(min(band[1] / (0.5 * fs), 0.9))
    low = zero_phase.filtfilt(b, a, values - values.mean())
    b, a = zero_phase.butter2(band[0] / (0.5 * fs))
    band = low - zero_phase.filtfilt(b, a, low)
    return band[:: max(int(round(fs / RATE)), 1)]


def cross_lag(y: np.ndarray, p: np.ndarray, rate: float) -> tuple[float, float, float]:
    """``(lag [s], r at the peak, curvature kappa [1/s^2])`` of ``y`` against ``p``
    (equal-length, zero-mean, sampled at ``rate``); ``y(t) ~ p(t - lag)``."""
    n = y.size
    most = min(int(MAX_LAG * rate), n // 3)
    lags = np.arange(-most, most + 1)
    r = np.empty(lags.size)
    for k, shift in enumerate(lags):
        a, b = (y[shift:], p[: n - shift]) if shift >= 0 else (y[: n + shift], p[-shift:])
        scale = math.sqrt(float(a @ a) * float(b @ b))
        r[k] = float(a @ b) / scale if scale > 0 else 0.0
    best = int(np.argmax(np.abs(r)))
    if best in (0, lags.size - 1):
        return lags[best] / rate, float(r[best]), 0.0
    left, centre, right = r[best - 1], r[best], r[best + 1]
    bend = left - 2.0 * centre + right
    offset = 0.5 * (left - right) / bend if bend != 0 else 0.0
    peak = centre - 0.25 * (left - right) * offset
    kappa = -bend * rate**2 / peak if peak != 0 else 0.0
    return (lags[best] + offset) / rate, float(peak), float(kappa)


def _lag(channel: str, against: str, key: str, y, p, fs: float) -> Lag:
    """The :class:`Lag` of band-passed ``y`` against band-passed ``p``."""
    y, p = _band(y, fs, BANDS[key]), _band(p, fs, BANDS[key])
    rate = fs / max(int(round(fs / RATE)), 1)
    if not np.std(p) > MIN_STD[key]:
        return Lag(channel=channel, against=against, lag=math.nan, std=math.nan,
                   correlation=math.nan, decided=False,
                   note=f"{against} varies too little")  # fmt: skip
    lag, r, kappa = cross_lag(y, p, rate)
    unaligned = float(y @ p) / math.sqrt(float(y @ y) * float(p @ p))
    independent = 2.0 * (BANDS[key][1] - BANDS[key][0]) * y.size / rate
    share = max(0.0, 1.0 - r * r)  # |r| may round a hair above 1 on a perfect match
    std = math.sqrt(share / (r * r * independent * kappa)) if kappa > 0 and r != 0 else math.inf
    note = ""
    if abs(r) < MIN_CORRELATION:
        note = f"correlation {abs(r):.2f} below {MIN_CORRELATION}"
    elif not std <= MAX_STD:
        note = f"lag uncertain (+-{std:.2g} s)"
    elif abs(lag) >= MAX_LAG - 1.0 / rate:
        note = f"no peak within {MAX_LAG:g} s"
    elif abs(lag) > LAG_TOLERANCE and (1 - unaligned**2) < MIN_MISFIT_RATIO * (1 - r * r):
        note = "a lag explains little of the misfit (grade, bank or slip)"
    return Lag(channel=channel, against=against, lag=lag, std=std, correlation=r,
               decided=not note, note=note)  # fmt: skip


def channel_lags(
    t: np.ndarray,
    vx: np.ndarray,
    acc: np.ndarray,
    d: np.ndarray,
    rates: np.ndarray | None = None,
) -> list[Lag]:
    """The lags of ``ay``, ``ax`` and the travels (module docstring) over the given
    samples (the wiring checks' window of motion); channels not logged are left out."""
    t = np.asarray(t, float)
    if t.size < 4 or not np.isfinite(t[[0, -1]]).all() or t[-1] - t[0] < 4.0:
        return []
    step = float(order_statistics.median(np.diff(t)))
    grid = np.arange(t[0], t[-1], step)
    fs = 1.0 / step
    on = lambda values: _uniform(t, np.asarray(values, float), grid)  # noqa: E731
    speed, ax, ay = on(vx), on(acc[:, 0]), on(acc[:, 1])
    lags = []
    if rates is not None and speed is not None and ay is not None:
        wz = on(rates[:, 2])
        if wz is not None:
            lags.append(_lag("ay", "vx wz", "ay", ay, speed * wz, fs))
    if speed is not None and ax is not None:
        lags.append(_lag("ax", "dvx/dt", "ax", ax, np.gradient(speed, step), fs))
    travel = [on(d[:, k]) for k in range(len(WHEELS))]
    if rates is not None and all(v is not None for v in travel):
        fl, fr, rl, rr = travel
        for key, axis, side in (("roll", 0, 0.5 * (fr + rr - fl - rl)),
                                ("pitch", 1, 0.5 * (fl + fr - rl - rr))):  # fmt: skip
            rate = on(rates[:, axis])
            if rate is not None:
                angle = np.cumsum(rate) * step
                lags.append(_lag(f"d ({key})", f"{key} angle from w{'xy'[axis]}", key,
                                 side, angle, fs))  # fmt: skip
    return lags
