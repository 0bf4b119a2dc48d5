r"""Per-channel lag against the physics the log already holds (cross-correlation).

A channel logged late (a CAN gateway, a filter inside a sensor) is found by
the lag :math:`\tau` that best aligns it with what other channels predict of it:

- ``ay`` against :math:`v_x \omega_z` (steady cornering; the lateral-velocity rate
  :math:`\dot v_y`, not logged, is small against it at the body's low frequencies);
- ``ax`` against :math:`\dot v_x` (level ground);
- the travels' roll, :math:`(d_{fr} + d_{rr} - d_{fl} - d_{rl})/2`, against the roll
  angle integrated from ``wx``, and their pitch, :math:`(d_{fl} + d_{fr} - d_{rl} -
  d_{rr})/2`, against the pitch angle from ``wy``: kinematics, no dynamics between.

Both sides are put on a uniform grid, band-passed (:data:`LOW_CUT` to
:data:`HIGH_CUT`, zero phase) and decimated to :data:`RATE`; the normalised
cross-correlation :math:`r(\tau)` is taken over :math:`|\tau| \le` :data:`MAX_LAG`
and its peak refined by a parabola through the three best lags. :math:`\tau > 0`:
the channel lags its prediction (shift its time stamps back by :math:`\tau`, the
channel map's ``latency`` key). Confidence: the peak correlation :math:`r` and the
standard error of the peak lag (Carter 1987, time-delay estimation),

.. math:: \sigma_\tau^2 = \frac{1 - r^2}{r^2 \, N \, \kappa},
   \qquad N = 2 B T, \quad \kappa = -\ddot r(\tau^*) / r(\tau^*),

with :math:`N` independent samples in the band :math:`B` over :math:`T` seconds and
:math:`\kappa` the peak's curvature. A lag is decided when :math:`|r| \ge`
:data:`MIN_CORRELATION`, :math:`\sigma_\tau \le` :data:`MAX_STD` and the predicting
side varies (:data:`MIN_STD`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kernels import zero_phase
from wheelload.models.conventions import WHEELS

LOW_CUT = 0.05  # Hz: slower drifts (an integrated gyro's) are removed
HIGH_CUT = 2.0  # Hz: the body's quasi-static response
RATE = 20.0  # Hz after band-pass and decimation
MAX_LAG = 1.0  # s
MIN_CORRELATION = 0.7
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


def _band(values: np.ndarray, fs: float) -> np.ndarray:
    """Zero-phase band-pass :data:`LOW_CUT` - :data:`HIGH_CUT`, decimated to :data:`RATE`."""
    b, a = zero_phase.butter2(min(HIGH_CUT / (0.5 * fs), 0.9))
    low = zero_phase.filtfilt(b, a, values - values.mean())
    b, a = zero_phase.butter2(LOW_CUT / (0.5 * fs))
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
    y, p = _band(y, fs), _band(p, fs)
    rate = fs / max(int(round(fs / RATE)), 1)
    if not np.std(p) > MIN_STD[key]:
        return Lag(channel=channel, against=against, lag=math.nan, std=math.nan,
                   correlation=math.nan, decided=False,
                   note=f"{against} varies too little")  # fmt: skip
    lag, r, kappa = cross_lag(y, p, rate)
    independent = 2.0 * (HIGH_CUT - LOW_CUT) * y.size / rate
    std = math.sqrt((1 - r * r) / (r * r * independent * kappa)) if kappa > 0 else math.inf
    note = ""
    if abs(r) < MIN_CORRELATION:
        note = f"correlation {abs(r):.2f} below {MIN_CORRELATION}"
    elif not std <= MAX_STD:
        note = f"lag uncertain (+-{std:.2g} s)"
    elif abs(lag) >= MAX_LAG - 1.0 / rate:
        note = f"no peak within {MAX_LAG:g} s"
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
    step = float(np.median(np.diff(t)))
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
