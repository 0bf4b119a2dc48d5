"""Logged signals: read a CSV or Parquet log into a validated :class:`Signals` set.

Columns (SI units): ``t`` [s], ``vx`` [m/s], ``ax ay az`` [m/s^2, specific
force in the body frame, gravity included], optional ``wx wy wz`` [rad/s]
and their derivative ``wx_dot wy_dot wz_dot`` [rad/s^2, else derived by
:func:`rate_derivatives` where needed],
``d_fl d_fr d_rl d_rr`` [m, compression], optional ``v_fl v_fr v_rl v_rr``
[m/s], optional hub accelerometers ``az_fl az_fr az_rl az_rr`` [m/s^2,
specific force along the body z axis, +9.81 at rest], optional reference
loads ``fz_fl fz_fr fz_rl fz_rr`` [N].

Missing suspension velocities are derived by a causal first-order filtered
differentiator, :math:`H(s) = \\omega_c s / (s + \\omega_c)` with
:math:`f_c = 20` Hz (Tustin), which passes body and wheel-hop motion
(1-15 Hz) and attenuates sensor noise above it.

Example
-------
>>> signals = read_log("drive.csv")
>>> signals.d.shape
(n, 4)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import signal as sp_signal

WHEELS = ("fl", "fr", "rl", "rr")
TRAVEL = tuple(f"d_{w}" for w in WHEELS)
TRAVEL_RATE = tuple(f"v_{w}" for w in WHEELS)
REFERENCE = tuple(f"fz_{w}" for w in WHEELS)
RATES = ("wx", "wy", "wz")
HUB = tuple(f"az_{w}" for w in WHEELS)
RATE_DERIVATIVES = ("wx_dot", "wy_dot", "wz_dot")
REQUIRED = ("t", "vx", "ax", "ay", "az", *TRAVEL)

VELOCITY_CUTOFF = 20.0  # Hz, differentiator corner frequency
MAX_SAMPLE_INTERVAL = 0.5  # s, longest median sample interval taken as seconds


class LogError(ValueError):
    """A log that cannot be used: names the file, the column and the row."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Signals:
    """A validated log: arrays of ``n`` samples, wheel order FL, FR, RL, RR."""

    t: np.ndarray  # (n,)
    vx: np.ndarray  # (n,)
    acc: np.ndarray  # (n, 3) ax, ay, az
    d: np.ndarray  # (n, 4)
    v: np.ndarray  # (n, 4)
    rates: np.ndarray | None = None  # (n, 3) wx, wy, wz
    reference: np.ndarray | None = None  # (n, 4) fz
    hub: np.ndarray | None = None  # (n, 4) hub specific force along body z
    rate_dots: np.ndarray | None = None  # (n, 3) logged derivative of wx, wy, wz
    velocities_derived: bool = False
    source: str = "<memory>"

    def __post_init__(self) -> None:
        n = np.shape(self.t)[0] if np.ndim(self.t) == 1 else -1
        shapes = {"t": (n,), "vx": (n,), "acc": (n, 3), "d": (n, 4), "v": (n, 4),
                  "rates": (n, 3), "reference": (n, 4), "hub": (n, 4),
                  "rate_dots": (n, 3)}  # fmt: skip
        for name, shape in shapes.items():
            value = getattr(self, name)
            if value is not None and np.shape(value) != shape:
                raise LogError(
                    f"{self.source}: '{name}' has shape {np.shape(value)}, expected {shape}"
                )
        _check_time(np.asarray(self.t, dtype=float), self.source)

    def __len__(self) -> int:
        return len(self.t)

    @property
    def sample_rate(self) -> float:
        """Median sample rate [Hz]."""
        return float(1.0 / np.median(np.diff(self.t)))

    def to_frame(self) -> pd.DataFrame:
        """The signals as a DataFrame with the log's column names."""
        columns = {"t": self.t, "vx": self.vx}
        columns.update(zip(("ax", "ay", "az"), self.acc.T))
        if self.rates is not None:
            columns.update(zip(RATES, self.rates.T))
        columns.update(zip(TRAVEL, self.d.T))
        columns.update(zip(TRAVEL_RATE, self.v.T))
        if self.rate_dots is not None:
            columns.update(zip(RATE_DERIVATIVES, self.rate_dots.T))
        if self.hub is not None:
            columns.update(zip(HUB, self.hub.T))
        if self.reference is not None:
            columns.update(zip(REFERENCE, self.reference.T))
        return pd.DataFrame(columns)

    def slice(self, start: int, stop: int) -> Signals:
        """Samples ``start:stop`` as a new signal set."""

        def cut(array):
            return None if array is None else array[start:stop]

        return Signals(
            t=self.t[start:stop],
            vx=self.vx[start:stop],
            acc=self.acc[start:stop],
            d=self.d[start:stop],
            v=self.v[start:stop],
            rates=cut(self.rates),
            reference=cut(self.reference),
            hub=cut(self.hub),
            rate_dots=cut(self.rate_dots),
            velocities_derived=self.velocities_derived,
            source=self.source,
        )


def read_log(path: str | Path, velocity_cutoff: float = VELOCITY_CUTOFF) -> Signals:
    """Read a ``.csv`` or ``.parquet`` log and validate it (see module docstring)."""
    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: no such log file")
    suffix = path.suffix.lower()
    try:
        if suffix == ".csv":
            frame = pd.read_csv(path, comment="#")
        elif suffix in (".parquet", ".pq"):
            frame = pd.read_parquet(path)
        else:
            raise LogError(f"{path}: unknown log format '{suffix}' (use .csv or .parquet)")
    except (pd.errors.ParserError, pd.errors.EmptyDataError, OSError) as error:
        raise LogError(f"{path}: cannot be read: {error}") from None
    return signals_from_frame(frame, source=str(path), velocity_cutoff=velocity_cutoff)


def signals_from_frame(
    frame: pd.DataFrame, source: str = "<frame>", velocity_cutoff: float = VELOCITY_CUTOFF
) -> Signals:
    """Validate a DataFrame with the log's columns and build :class:`Signals`."""
    frame = frame.rename(columns=lambda name: str(name).strip())
    for name in REQUIRED:
        if name not in frame.columns:
            raise LogError(f"{source}: missing column '{name}'")

    def column(name: str) -> np.ndarray:
        kind = frame[name].dtype
        if not (
            pd.api.types.is_numeric_dtype(kind)
            or pd.api.types.is_object_dtype(kind)
            or pd.api.types.is_string_dtype(kind)
        ) or pd.api.types.is_bool_dtype(kind):
            raise LogError(
                f"{source}: column '{name}' has type {kind}: give plain numbers in SI units"
            )  # fmt: skip
        values = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(np.isnan(values) & frame[name].notna().to_numpy())
        if bad.size:
            raise LogError(
                f"{source}: column '{name}' is not numeric at row {bad[0]}: "
                f"{frame[name].iloc[bad[0]]!r}"
            )
        return values

    def group(names: tuple[str, ...]) -> np.ndarray | None:
        present = [name for name in names if name in frame.columns]
        if not present:
            return None
        if len(present) != len(names):
            missing = [name for name in names if name not in frame.columns]
            raise LogError(
                f"{source}: has column '{present[0]}' but not '{missing[0]}': "
                f"give all of {', '.join(names)} or none"
            )
        return np.column_stack([column(name) for name in names])

    t = column("t")
    _check_time(t, source)
    step = float(np.median(np.diff(t)))
    if step > MAX_SAMPLE_INTERVAL:
        raise LogError(
            f"{source}: column 't' advances by {step:.4g} per sample: more than "
            f"{MAX_SAMPLE_INTERVAL} s, it looks like milliseconds (give seconds)"
        )
    acc = np.column_stack([column(name) for name in ("ax", "ay", "az")])
    d = group(TRAVEL)
    v = group(TRAVEL_RATE)
    signals_vx = column("vx")
    _check_units(acc, d, v, signals_vx, source)
    derived = v is None
    if derived:
        v = derive_velocities(t, d, velocity_cutoff, source)
    return Signals(
        t=t,
        vx=signals_vx,
        acc=acc,
        d=d,
        v=v,
        rates=group(RATES),
        reference=group(REFERENCE),
        hub=group(HUB),
        rate_dots=group(RATE_DERIVATIVES),
        velocities_derived=derived,
        source=source,
    )


def _check_time(t: np.ndarray, source: str) -> None:
    if t.size < 2:
        raise LogError(f"{source}: needs at least 2 samples, has {t.size}")
    missing = np.flatnonzero(~np.isfinite(t))
    if missing.size:
        raise LogError(f"{source}: column 't' has no valid time stamp at row {missing[0]}")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        row = bad[0] + 1
        raise LogError(
            f"{source}: column 't' is not increasing at row {row} "
            f"(t = {t[row - 1]!r} then {t[row]!r})"
        )


def _check_units(acc, d, v, vx, source: str) -> None:
    """Report values that look like the wrong unit rather than guess."""
    az = np.nanmedian(acc[:, 2]) if np.any(np.isfinite(acc[:, 2])) else np.nan
    if np.isfinite(az) and 0.5 < abs(az) < 2.0:
        raise LogError(
            f"{source}: column 'az' has median {az:.3g}: it looks like g units; "
            "give specific force in m/s^2 (about +9.81 at rest)"
        )
    if np.isfinite(az) and not 4.0 < az < 20.0:
        raise LogError(
            f"{source}: column 'az' has median {az:.3g} m/s^2: expected specific force "
            "including gravity, about +9.81 at rest with z up"
        )
    for name, values, limit, unit in (
        ("d", d, 0.3, "mm"),
        ("v", v, 10.0, "mm/s"),
    ):
        if values is None:
            continue
        peaks = np.nanmax(np.abs(values), axis=0, initial=0.0)
        for wheel, peak in zip(WHEELS, peaks):
            if peak > limit:
                raise LogError(
                    f"{source}: column '{name}_{wheel}' reaches {peak:.3g}: more than "
                    f"{limit} in SI units, it looks like {unit}"
                )
    if np.nanmax(np.abs(vx), initial=0.0) > 120.0:
        raise LogError(
            f"{source}: column 'vx' reaches {np.nanmax(np.abs(vx)):.4g}: more than 120 m/s, "
            "it looks like km/h"
        )


def derive_velocities(
    t: np.ndarray, d: np.ndarray, cutoff: float = VELOCITY_CUTOFF, source: str = "<log>"
) -> np.ndarray:
    r"""Causal filtered derivative of the travel, :math:`\omega_c s/(s+\omega_c)` (Tustin).

    Needs near-uniform sampling (jitter below 5 % of the median interval). A
    missing travel sample gives a missing velocity, and the filter restarts at
    rest on the first sample after a gap, so a gap makes no false velocity.
    """
    dt = np.diff(t)
    median = float(np.median(dt))
    if np.max(np.abs(dt - median)) > 0.05 * median:
        raise LogError(
            f"{source}: time stamps are not uniform enough to derive suspension velocities; "
            "give columns v_fl v_fr v_rl v_rr"
        )
    nyquist = 0.5 / median
    if cutoff >= 0.8 * nyquist:
        raise LogError(
            f"{source}: sample rate {1 / median:.4g} Hz is too low for the {cutoff} Hz "
            "velocity differentiator; give columns v_fl v_fr v_rl v_rr"
        )
    omega = 2.0 * np.pi * cutoff
    b, a = sp_signal.bilinear([omega, 0.0], [1.0, omega], fs=1.0 / median)
    rest = sp_signal.lfilter_zi(b, a)
    v = np.full(d.shape, np.nan)
    for wheel in range(d.shape[1]):
        for start, stop in _valid_runs(np.isfinite(d[:, wheel])):
            run = d[start:stop, wheel]
            v[start:stop, wheel], _ = sp_signal.lfilter(b, a, run, zi=rest * run[0])
    return v


def _valid_runs(valid: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of consecutive True values."""
    edges = np.diff(np.concatenate([[0], valid.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def write_log(signals: Signals, path: str | Path) -> None:
    """Write signals as ``.csv`` or ``.parquet`` with the log's column names."""
    path = Path(path)
    frame = signals.to_frame()
    if path.suffix.lower() == ".csv":
        frame.to_csv(path, index=False)
    elif path.suffix.lower() in (".parquet", ".pq"):
        frame.to_parquet(path, index=False)
    else:
        raise LogError(f"{path}: unknown log format '{path.suffix}' (use .csv or .parquet)")


def rate_derivatives(signals: Signals, cutoff: float = VELOCITY_CUTOFF) -> np.ndarray:
    r"""Causal filtered derivative of the body rates ``wx wy wz``, shape (n, 3) [rad/s^2].

    The logged ``wx_dot wy_dot wz_dot`` when present, else the same
    differentiator as :func:`derive_velocities`. All NaN where the log has no
    rates or its time stamps are too irregular to differentiate: the terms
    that need them are then dropped and flagged, not guessed.
    """
    if signals.rate_dots is not None:
        return signals.rate_dots
    if signals.rates is None:
        return np.full((len(signals), 3), np.nan)
    try:
        return derive_velocities(signals.t, signals.rates, cutoff, signals.source)
    except LogError:
        return np.full((len(signals), 3), np.nan)
