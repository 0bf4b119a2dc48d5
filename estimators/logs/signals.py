"""Logged signals: read a log into a validated :class:`Signals` set.

Columns (SI units): ``t`` [s], ``ax ay`` [m/s^2, specific force in the body
frame], optional ``az`` [m/s^2, gravity included], optional ``vx`` [m/s],
optional ``wx wy wz`` [rad/s] and their derivative ``wx_dot wy_dot wz_dot``
[rad/s^2, else derived by :func:`rate_derivatives` where needed], optional
``d_fl d_fr d_rl d_rr`` [m, compression], optional ``v_fl v_fr v_rl v_rr``
[m/s], optional hub accelerometers ``az_fl az_fr az_rl az_rr`` [m/s^2,
specific force along the body z axis, +9.81 at rest], optional reference
loads ``fz_fl fz_fr fz_rl fz_rr`` [N] (any of them), optional wheel speeds
``ws_fl ..`` [m/s]; for the tyre-force estimators, optional wheel spins ``omega_fl ..``
[rad/s], drive/brake torque on each wheel ``torque_fl ..`` [N m, > 0 drives forward],
front road-wheel angle ``steer`` [rad, > 0 to the left] and reference tyre forces
``fx_fl .. fy_rr`` [N, each tyre's frame, ISO 8855: x along the wheel heading in the road
plane, y to its left]. CSV and Parquet logs with these column names are read as
they are; any other log (MDF4, CarMaker ERG, other names or units) through a
channel map (``estimators/logs/readers``), ``read_log(path, channels=MAP)``.

Partial sensor sets (:class:`TravelSensors`, named in summaries): without
travel columns (or with a travel column empty) the suspension updates of
those corners are skipped (IMU-only when none is left); without ``az``,
:math:`a_z = g` is assumed (flag ``AZ_ASSUMED_G``); without ``vx`` it is the
mean of the wheel speeds (``SPEED_FROM_WHEELS``) or, without those, zero, so
that the aerodynamic terms are off (``AERO_OFF_NO_SPEED``). A model term whose
optional input is missing is dropped for that sample (flag bits 16-19).

Missing suspension velocities are derived by a causal first-order filtered
differentiator, :math:`H(s) = \\omega_c s / (s + \\omega_c)` with
:math:`f_c = 20` Hz (Tustin), which passes body and wheel-hop motion
(1-15 Hz) and attenuates sensor noise above it. A gap in the time stamps (a step
longer than 1.5 median intervals, :data:`~wheelload.estimators.types.GAP_RATIO`) splits the
log into segments: the differentiator and the body-rate derivative filter restart after it,
and the filter's step over it is flagged ``INTERVAL_LONG``; the log is never refused for it.

Example
-------
>>> signals = read_log("drive.csv")
>>> signals.d.shape
(n, 4)
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators.kernels import first_order, kinematic, order_statistics
from wheelload.estimators.logs.checks import check_wiring, duplicate_columns, raise_for_wiring
from wheelload.estimators.logs.own_clocks import on_own_stamps
from wheelload.estimators.types import (
    HUB,
    RATE_DERIVATIVES,
    RATES,
    REFERENCE,
    REFERENCE_FX,
    REFERENCE_FY,
    REQUIRED,
    SPIN,
    STEER,
    TORQUE,
    TRAVEL,
    TRAVEL_RATE,
    WHEEL_SPEED,
    LogError,
    Signals,
    SpeedSource,
    Steps,
    check_time_column,
)
from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.models.vehicle.sensor_section import MTI_1_GYRO_NOISE_DENSITY

if TYPE_CHECKING:
    import pandas as pd

    from wheelload.models.vehicle.description import Vehicle


VELOCITY_CUTOFF = 20.0  # Hz, differentiator corner frequency
_log = logging.getLogger("wheelload")


def travel_quantum(d: np.ndarray) -> np.ndarray:
    """(4,) the logger step of each travel channel [m]: the smallest difference between
    two of its distinct finite values (NaN with fewer than two).

    A travel logged as integers (``int16`` mm, raw converter counts) moves in steps of
    this size: a corner on a still body shows no change for long, or flickers by a step,
    however still it is. The fault monitor's stuck test (``estimators/guards/settings.py``) needs
    it to tell a quiet quantised channel from a stuck one.
    """
    steps = np.full(d.shape[1], np.nan)
    for k in range(d.shape[1]):
        values = np.unique(d[np.isfinite(d[:, k]), k])
        if values.size > 1:
            steps[k] = float(np.min(np.diff(values)))
    return steps


def coarse_travel_note(quantum: np.ndarray | None, stuck_motion: float) -> str | None:
    """A line for a travel logged in steps above a quarter of the stuck test's motion
    threshold (``GuardSettings.stuck_motion``, 4 steps of a 12-bit sensor), else None:
    quiet corners of such a log may be isolated as stuck (``travel_fault``)."""
    if quantum is None or not np.any(quantum > 0.25 * stuck_motion):
        return None
    shown = " ".join(
        f"{w.upper()} {1000 * q:.3g} mm" for w, q in zip(WHEELS, quantum) if np.isfinite(q)
    )
    return (
        f"travel logged in steps of {shown}: coarser than the stuck test expects "
        f"({1000 * stuck_motion:.3g} mm = 4 steps); a quiet corner may be flagged travel_fault"
    )


def read_log(
    path: str | Path,
    velocity_cutoff: float = VELOCITY_CUTOFF,
    *,
    channels: str | Path | None = None,
    wiring_checks: bool = True,
) -> Signals:
    """Read a log (CSV, Parquet, MDF4, ERG) and validate it (see module docstring).

    ``channels`` is a channel-map TOML file (``wheelload channels --template``);
    without it the log's channels must be named as ours, in SI units.
    ``wiring_checks``: run :mod:`wheelload.estimators.logs.checks` (signs, units, wiring).
    """
    import pandas as pd

    from wheelload.estimators.logs.readers import ChannelMapError, load_channel_map, read_frame

    path = Path(path)
    if not path.exists():
        raise LogError(f"{path}: no such log file")
    try:
        channel_map = load_channel_map(channels) if channels is not None else None
        frame = read_frame(path, channel_map)
    except ChannelMapError as error:
        raise LogError(str(error)) from None
    except UnicodeDecodeError as error:
        raise LogError(
            f"{path}: is not UTF-8 text (byte {error.start}): save the log as UTF-8 CSV"
        ) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, OSError) as error:
        raise LogError(f"{path}: cannot be read: {error}") from None
    except ValueError as error:  # pandas: a column named in a map is not in the file
        raise LogError(f"{path}: cannot be read: {error}") from None
    return signals_from_frame(
        frame,
        source=str(path),
        velocity_cutoff=velocity_cutoff,
        wiring_checks=wiring_checks,
        own_clocks=channel_map is not None and channel_map.clock.union,
    )


def signals_from_frame(
    frame: pd.DataFrame,
    source: str = "<frame>",
    velocity_cutoff: float = VELOCITY_CUTOFF,
    *,
    wiring_checks: bool = True,
    own_clocks: bool = False,
) -> Signals:
    """Validate a DataFrame with the log's columns and build :class:`Signals`; ``own_clocks``:
    its channels are on their own clocks, NaN where one has no new value (``[clock] union``)."""
    import pandas as pd

    duplicate = duplicate_columns(frame.columns)
    if duplicate is not None:
        raise LogError(
            f"{source}: column '{duplicate}' appears twice: keep one (which copy is meant?)"
        )
    frame = frame.rename(columns=lambda name: str(name).strip())
    for name in REQUIRED:
        if name not in frame.columns:
            raise LogError(
                f"{source}: missing column '{name}' "
                "(a logger's names: give a channel map, --channels)"
            )

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
        if pd.api.types.is_numeric_dtype(kind):
            return frame[name].to_numpy(dtype=float, na_value=np.nan)  # nothing to coerce
        values = pd.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(np.isnan(values) & frame[name].notna().to_numpy())
        if bad.size:
            raise LogError(
                f"{source}: column '{name}' is not numeric at row {bad[0]}: "
                f"{frame[name].iloc[bad[0]]!r}"
            )
        return values

    def group(names: tuple[str, ...], partial: bool = False) -> np.ndarray | None:
        present = [name for name in names if name in frame.columns]
        if not present:
            return None
        if partial:  # a missing column is a channel with no sample
            return np.column_stack(
                [column(n) if n in frame.columns else np.full(len(frame), np.nan) for n in names]
            )
        if len(present) != len(names):
            missing = [name for name in names if name not in frame.columns]
            raise LogError(
                f"{source}: has column '{present[0]}' but not '{missing[0]}': "
                f"give all of {', '.join(names)} or none"
            )
        return np.column_stack([column(name) for name in names])

    t = time_seconds(frame["t"]) if is_time_stamp(frame["t"]) else column("t")
    steps = check_time_column(t, source)
    missing = np.full((t.size, 4), np.nan)
    for name in REQUIRED[1:]:
        if not np.isfinite(column(name)).any():
            raise LogError(
                f"{source}: column '{name}' has no values: the filter needs {name} "
                "(log the IMU's axis, or map its channel with --channels)"
            )
    az_assumed = "az" not in frame.columns or not np.isfinite(column("az")).any()
    az = np.full(t.size, GRAVITY) if az_assumed else column("az")
    acc = np.column_stack([column("ax"), column("ay"), az])
    imu = np.isfinite(acc[:, 0])
    if not own_clocks:
        say_gaps(steps, source)
    elif imu.sum() > 1:
        say_gaps(Steps.of(t[imu]), source, own_clocks=True)
    d = group(TRAVEL)
    d = missing if d is None else d
    v = group(TRAVEL_RATE)
    if "vx" in frame.columns and np.isfinite(column("vx")).any():
        speed, speed_source = (
            slow_channel(t, column("vx"), "vx", source, own_clock=own_clocks),
            SpeedSource.LOGGED,
        )
    elif any(name in frame.columns for name in WHEEL_SPEED):
        wheels = np.column_stack([column(n) for n in WHEEL_SPEED if n in frame.columns])
        finite = np.isfinite(wheels)
        count = finite.sum(axis=1)
        total = np.where(finite, wheels, 0.0).sum(axis=1)
        speed = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        speed = slow_channel(t, speed, "ws_*", source, own_clock=own_clocks)
        speed_source = SpeedSource.WHEEL_SPEEDS
    else:
        speed, speed_source = np.zeros(t.size), SpeedSource.NONE
    check_units(acc, d, v, speed, source)
    if wiring_checks:
        report = check_wiring(t, speed, acc, d, group(RATES, partial=True), own_clocks=own_clocks)
        raise_for_wiring(report, source)
    derived = v is None and bool(np.isfinite(d).any())
    if derived:
        v = derive_velocities(t, d, velocity_cutoff, source, own_clocks=own_clocks)
    elif v is None:
        v = missing.copy()
    return Signals(
        t=t,
        vx=speed,
        acc=acc,
        d=d,
        v=v,
        rates=group(RATES, partial=True),  # any subset of wx wy wz: the others missing
        reference=group(REFERENCE, partial=True),
        hub=group(HUB),
        rate_dots=group(RATE_DERIVATIVES, partial=True),
        velocities_derived=derived,
        source=source,
        az_assumed=az_assumed,
        speed_source=speed_source,
        travel_quantum=travel_quantum(d),
        spin=group(SPIN, partial=True),
        torque=group(TORQUE, partial=True),
        steer=column(STEER) if STEER in frame.columns else None,
        reference_fx=group(REFERENCE_FX, partial=True),
        reference_fy=group(REFERENCE_FY, partial=True),
        own_clocks=own_clocks,
    )


def say_gaps(steps: Steps, source: str, *, own_clocks: bool = False) -> None:
    """A note on the ``wheelload`` logger for a log whose time stamps have gaps (steps longer
    than :data:`~wheelload.estimators.types.GAP_RATIO` median intervals): it is run as
    segments, the derived channels restarted after each gap, the step over it flagged.
    ``own_clocks``: ``steps`` are the IMU's own (channels on their own clocks), each channel's
    derived values restart after its own gaps and the filter predicts over them."""
    if not steps.gaps:
        return
    where, then = (
        ("the IMU's own time stamps", "each channel's derived values restarted after its own")
        if own_clocks
        else ("the time stamps", "derived velocities restarted after each, the step over it "
              "flagged INTERVAL_LONG")
    )  # fmt: skip
    _log.warning(
        "%s: note: %d gap(s) in %s (longest %.3g s, %.0f sample intervals): run as %d "
        "segments, %s",
        source, steps.gaps, where, steps.longest_gap, steps.longest_gap / steps.median,
        steps.gaps + 1, then,
    )  # fmt: skip


#: s, the longest interval over which a slow channel is interpolated between two samples.
SLOW_CHANNEL_GAP = 2.0


def slow_channel(
    t: np.ndarray, values: np.ndarray, name: str, source: str, *, own_clock: bool = False
) -> np.ndarray:
    """A slowly varying channel (the speed) logged at a lower rate than the log's clock
    (NaN where it has no new value) interpolated linearly between its own samples, up to
    :data:`SLOW_CHANNEL_GAP` apart; a channel with a value at more than half the rows is
    returned as it is (its missing samples are dropouts, skipped and flagged), unless it is
    on its own clock (``own_clock``: a row without a value is another channel's). Says so on
    the ``wheelload`` logger (a note)."""
    good = np.isfinite(values)
    if (good.sum() > 0.5 * values.size and not own_clock) or good.sum() < 2:
        return values
    from wheelload.estimators.logs.readers.resample import Method, resample

    rate = (good.sum() - 1) / float(t[good][-1] - t[good][0])
    _log.warning(
        "%s: note: column '%s' has a value at %d of %d rows (%.3g Hz): interpolated linearly "
        "between its samples onto the log's clock (up to %g s apart)",
        source, name, int(good.sum()), values.size, rate, SLOW_CHANNEL_GAP,
    )  # fmt: skip
    return resample(t[good], values[good], t, Method.LINEAR, SLOW_CHANNEL_GAP)


def is_time_stamp(values: pd.Series) -> bool:
    """Whether a time column holds date-time stamps (Parquet ``timestamp[ns/us/ms]``, with or
    without a time zone) or durations (``duration[..]``), not numbers of seconds."""
    import pandas as pd

    kind = values.dtype
    types = pd.api.types
    return bool(types.is_datetime64_any_dtype(kind) or types.is_timedelta64_dtype(kind))


def time_seconds(values: pd.Series) -> np.ndarray:
    """Date-time stamps or durations as seconds from the first one (float64, from integer
    nanoseconds: a day-long log keeps better than a microsecond); a missing stamp is NaN."""
    import pandas as pd

    if pd.api.types.is_timedelta64_dtype(values.dtype):
        nanoseconds = values.astype("timedelta64[ns]").to_numpy().astype("int64")
    else:
        if values.dt.tz is not None:
            values = values.dt.tz_convert("UTC").dt.tz_localize(None)
        nanoseconds = values.astype("datetime64[ns]").to_numpy().astype("int64")
    valid = values.notna().to_numpy()
    if not valid.any():
        return np.full(values.size, np.nan)
    seconds = (nanoseconds - nanoseconds[valid][0]) * 1e-9
    return np.where(valid, seconds, np.nan)


def check_units(acc, d, v, vx, source: str) -> None:
    """Report values that look like the wrong unit rather than guess."""
    az = order_statistics.nanmedian(acc[:, 2]) if np.any(np.isfinite(acc[:, 2])) else np.nan
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
    t: np.ndarray,
    d: np.ndarray,
    cutoff: float = VELOCITY_CUTOFF,
    source: str = "<log>",
    *,
    own_clocks: bool = False,
) -> np.ndarray:
    r"""Causal filtered derivative of the travel, :math:`\omega_c s/(s+\omega_c)` (Tustin).

    Needs near-uniform sampling within each segment (jitter below 5 % of the median
    interval; a longer step is a gap between segments). A missing travel sample gives a
    missing velocity, and the filter restarts at rest on the first sample after a missing
    sample or a time gap, so a gap makes no false velocity. With ``own_clocks`` (channels
    on their own clocks, NaN where a channel has no new value) each travel is differentiated
    on its own time stamps (:func:`on_own_stamps`).
    """
    if not np.isfinite(d).any():
        return np.full(d.shape, np.nan)
    if own_clocks:
        return on_own_stamps(
            lambda steps, name: Differentiator(steps, 1, cutoff, f"{source}: channel '{name}'"),
            t, d, TRAVEL,
        )  # fmt: skip
    return Differentiator(Steps.of(t), d.shape[1], cutoff, source)(d, t)


class ChunkFilter:
    """A causal per-channel filter run over consecutive chunks of a log with its state carried.

    Called on consecutive chunks (2-D, one column per channel), it returns what one
    call on the whole log returns, to the bit: each run of finite samples is filtered
    with the state it left at the end of the previous chunk; a run after a gap starts
    afresh (:meth:`start`). A gap is a missing sample, or, given the time stamps ``t``,
    a step longer than ``gap`` seconds (a logger pause: the log's next segment).
    Subclasses give :meth:`start` and :meth:`filter`.
    """

    def __init__(self, channels: int, gap: float = np.inf) -> None:
        self._state: list[np.ndarray | None] = [None] * channels  # None: not inside a run
        self._gap = gap
        self._last: float | None = None  # the previous chunk's last time stamp

    def start(self, first: float) -> np.ndarray:
        """The state before a run whose first sample is ``first``."""
        raise NotImplementedError

    def filter(self, run: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(outputs, state at the end)`` of one run of finite samples."""
        raise NotImplementedError

    def _segment_starts(self, t: np.ndarray | None, n: int) -> np.ndarray:
        """Rows of this chunk that start a segment (a step longer than the gap before them)."""
        if t is None or n == 0:
            return np.zeros(n, bool)
        previous = np.concatenate([[np.nan if self._last is None else self._last], t[:-1]])
        self._last = float(t[-1])
        return t - previous > self._gap

    def __call__(self, samples: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """Outputs of the next chunk (rows: samples, columns: channels); NaN where missing."""
        out = np.full(samples.shape, np.nan)
        starts = self._segment_starts(t, samples.shape[0])
        for channel in range(samples.shape[1]):
            valid = np.isfinite(samples[:, channel])
            carried = self._state[channel]
            for start, stop in _valid_runs(valid, starts):
                run = samples[start:stop, channel]
                fresh = start > 0 or carried is None or starts[start]
                state = self.start(run[0]) if fresh else carried
                out[start:stop, channel], carried = self.filter(run, state)
            self._state[channel] = carried if valid.size and valid[-1] else None
        return out


class Differentiator(ChunkFilter):
    r"""The travel differentiator of :func:`derive_velocities` with its state carried
    (:class:`ChunkFilter`). ``steps``: the whole log's sample intervals (:class:`Steps`,
    for the uniformity and sample-rate checks).
    """

    def __init__(
        self,
        steps: Steps,
        channels: int,
        cutoff: float = VELOCITY_CUTOFF,
        source: str = "<log>",
    ) -> None:
        super().__init__(channels, steps.gap)
        median = steps.median
        if not steps.uniform():
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
        # scipy.signal's bilinear, lfilter_zi and lfilter to the bit, without its import.
        self._b, self._a = first_order.bilinear_differentiator(omega, 1.0 / median)
        self._rest = first_order.lfilter_zi(self._b, self._a)

    def start(self, first: float) -> np.ndarray:
        return self._rest * first

    def filter(self, run: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return first_order.lfilter(self._b, self._a, run, state)


@dataclass(frozen=True, kw_only=True)
class RateDerivativeFilter:
    r"""Settings of the body-rate derivative estimator (:class:`RateEstimator`).

    The kinematic filter of :mod:`~wheelload.estimators.kernels.kinematic` with jerk
    density :math:`q` and the gyroscope's white noise to the Nyquist frequency,
    :math:`r = N^2 / (2 T)`: its bandwidth follows the sample rate and the noise.
    The defaults are a file's without ``[filter] rate_jerk_density`` and ``[sensors]``
    (an MTi-1 class gyroscope); :meth:`of` takes a vehicle file's.
    """

    jerk_density: float = 1.0  # q [(rad/s^3)^2/Hz]
    gyro_noise_density: float = MTI_1_GYRO_NOISE_DENSITY  # N [rad/s/sqrt(Hz)]

    @classmethod
    def of(cls, vehicle: Vehicle) -> RateDerivativeFilter:
        """The settings a vehicle file states (``[filter]`` and ``[sensors]``)."""
        return cls(
            jerk_density=vehicle.filter.rate_jerk_density,
            gyro_noise_density=vehicle.sensors.gyro_noise_density,
        )

    def gain(self, interval: float) -> np.ndarray:
        """The steady-state gain at the sample interval ``interval`` [s]."""
        noise = self.gyro_noise_density**2 / (2.0 * interval)
        return kinematic.steady_gain(interval, self.jerk_density, noise)


#: A vehicle file's without ``[filter] rate_jerk_density`` and ``[sensors]``.
DEFAULT_RATE_FILTER = RateDerivativeFilter()


class RateEstimator(ChunkFilter):
    r"""Body-rate derivatives estimated by a kinematic Kalman filter per axis
    (:class:`RateDerivativeFilter`), its state carried over chunks (:class:`ChunkFilter`);
    a run after a gap starts at the rate held, :math:`[w_0, 0]`.
    ``steps``: the whole log's sample intervals (:class:`Steps`, for the uniformity check).
    """

    def __init__(
        self,
        steps: Steps,
        channels: int = 3,
        source: str = "<log>",
        settings: RateDerivativeFilter = DEFAULT_RATE_FILTER,
    ) -> None:
        super().__init__(channels, steps.gap)
        median = steps.median
        if not steps.uniform():
            raise LogError(
                f"{source}: time stamps are not uniform enough to estimate body-rate "
                "derivatives; give columns wx_dot wy_dot wz_dot"
            )
        self._interval = median
        self._gain = settings.gain(median)

    def start(self, first: float) -> np.ndarray:
        return np.array([first, 0.0])

    def filter(self, run: np.ndarray, state: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return kinematic.kinematic_filter(self._interval, self._gain, run, state)


def _valid_runs(valid: np.ndarray, starts: np.ndarray | None = None) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of consecutive True values, split before each row
    where ``starts`` is True."""
    edges = np.diff(np.concatenate([[0], valid.astype(np.int8), [0]]))
    runs = list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))
    if starts is None or not np.any(starts):
        return runs
    cuts = np.flatnonzero(starts)
    split = []
    for start, stop in runs:
        inner = cuts[(cuts > start) & (cuts < stop)]
        bounds = [start, *inner.tolist(), stop]
        split += list(zip(bounds[:-1], bounds[1:]))
    return split


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


def rate_derivatives(
    signals: Signals, settings: RateDerivativeFilter = DEFAULT_RATE_FILTER
) -> np.ndarray:
    r"""Estimated derivatives of the body rates ``wx wy wz``, shape (n, 3) [rad/s^2].

    The logged ``wx_dot wy_dot wz_dot`` when present, else the causal kinematic
    filter of :class:`RateEstimator` with ``settings`` (not a differentiator: a filtered
    derivative of a noisy gyro at 20 Hz carries more noise into the body-inertia term than
    the term is worth), each rate on its own stamps for channels on their own clocks. All
    NaN where the log has no rates or its time stamps are too irregular: the terms that need
    them are then dropped and flagged, not guessed.
    """
    if signals.rate_dots is not None:
        return signals.rate_dots
    if signals.rates is None or len(signals) < 2:
        return np.full((len(signals), 3), np.nan)
    try:
        if signals.own_clocks:  # each rate on its own stamps
            return on_own_stamps(
                lambda steps, name: RateEstimator(steps, 1, signals.source, settings),
                signals.t, signals.rates, RATES,
            )  # fmt: skip
        estimator = RateEstimator(Steps.of(signals.t), 3, signals.source, settings)
        return estimator(signals.rates, signals.t)
    except LogError:
        return np.full((len(signals), 3), np.nan)
