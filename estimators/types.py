"""Plain types of the estimators' interface: a validated log (:class:`Signals`), one sample
(:class:`Sample`), the log format's channel names and the time-column checks.

Nothing here reads a file or runs a filter: the readers (``estimators/logs``) build these,
the estimators (``estimators/kf``, ``mhe``, ``family``) take them. Columns, units and the
partial sensor sets are described in :mod:`wheelload.estimators.logs.signals`.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.result import StepFlag
from wheelload.models.conventions import WHEELS
from wheelload.models.runtime.spill import release

if TYPE_CHECKING:
    import pandas as pd

TRAVEL = tuple(f"d_{w}" for w in WHEELS)


TRAVEL_RATE = tuple(f"v_{w}" for w in WHEELS)


REFERENCE = tuple(f"fz_{w}" for w in WHEELS)


WHEEL_SPEED = tuple(f"ws_{w}" for w in WHEELS)


SPIN = tuple(f"omega_{w}" for w in WHEELS)


TORQUE = tuple(f"torque_{w}" for w in WHEELS)


REFERENCE_FX = tuple(f"fx_{w}" for w in WHEELS)


REFERENCE_FY = tuple(f"fy_{w}" for w in WHEELS)


STEER = "steer"


RATES = ("wx", "wy", "wz")


HUB = tuple(f"az_{w}" for w in WHEELS)


RATE_DERIVATIVES = ("wx_dot", "wy_dot", "wz_dot")


REQUIRED = ("t", "ax", "ay")


MAX_SAMPLE_INTERVAL = 0.5  # s, longest median sample interval taken as seconds


class LogError(ValueError):
    """A log that cannot be used: names the file, the column and the row."""


class TravelSensors(enum.Enum):
    """Which suspension travel sensors a log has (a sensor with no finite sample is absent)."""

    ALL = "four travel sensors"
    DEAD_CORNER = "three travel sensors (one corner dead)"
    TWO = "two travel sensors"
    ONE = "one travel sensor"
    NONE = "no travel sensors (IMU-only)"


class SpeedSource(enum.Enum):
    """Where ``vx`` comes from."""

    LOGGED = "logged"
    WHEEL_SPEEDS = "mean of the wheel speeds"
    NONE = "none (aerodynamic terms off)"


def sensor_mode(travel_present: np.ndarray, az_assumed: bool, speed_source: SpeedSource) -> str:
    """The sensor set in words, for summaries (see :meth:`Signals.mode`)."""
    count = int(np.sum(travel_present))
    parts = [(TravelSensors.NONE, TravelSensors.ONE, TravelSensors.TWO,
              TravelSensors.DEAD_CORNER, TravelSensors.ALL)[count].value]  # fmt: skip
    if 0 < count < 4:
        missing = [w.upper() for w, ok in zip(WHEELS, travel_present) if not ok]
        parts[0] += f", missing {' '.join(missing)}"
    if az_assumed:
        parts.append("no az: g assumed")
    if speed_source is not SpeedSource.LOGGED:
        parts.append(f"vx: {speed_source.value}")
    return "; ".join(parts)


def input_bits(az_assumed: bool, speed_source: SpeedSource) -> int:
    """:class:`StepFlag` bits of inputs the log did not have (az, vx)."""
    bits = 0
    if az_assumed:
        bits |= StepFlag.AZ_ASSUMED_G
    if speed_source is SpeedSource.WHEEL_SPEEDS:
        bits |= StepFlag.SPEED_FROM_WHEELS
    if speed_source is SpeedSource.NONE:
        bits |= StepFlag.AERO_OFF_NO_SPEED
    return int(bits)


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
    az_assumed: bool = False
    speed_source: SpeedSource = SpeedSource.LOGGED
    travel_quantum: np.ndarray | None = None  # (4,) logger step of d_* [m] (travel_quantum)
    # Tyre-force channels (module docstring), each None when the log lacks it.
    spin: np.ndarray | None = None  # (n, 4) omega_* [rad/s]
    torque: np.ndarray | None = None  # (n, 4) torque_* [N m]
    steer: np.ndarray | None = None  # (n,) front road-wheel angle [rad]
    reference_fx: np.ndarray | None = None  # (n, 4) fx_* [N], tyre frame
    reference_fy: np.ndarray | None = None  # (n, 4) fy_* [N], tyre frame
    #: Channels on their own clocks (``[clock] union``): each NaN where it has no new value;
    #: derivatives on each channel's own stamps, the KF at each row's own time stamp.
    own_clocks: bool = False

    def __post_init__(self) -> None:
        n = np.shape(self.t)[0] if np.ndim(self.t) == 1 else -1
        shapes = {"t": (n,), "vx": (n,), "acc": (n, 3), "d": (n, 4), "v": (n, 4),
                  "rates": (n, 3), "reference": (n, 4), "hub": (n, 4),
                  "rate_dots": (n, 3), "spin": (n, 4), "torque": (n, 4), "steer": (n,),
                  "reference_fx": (n, 4), "reference_fy": (n, 4)}  # fmt: skip
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
    def travel_present(self) -> np.ndarray:
        """(4,) True for each corner whose travel channel has a finite sample."""
        return np.any(np.isfinite(self.d), axis=0)

    @property
    def reference_present(self) -> np.ndarray:
        """(4,) True for each wheel whose reference load ``fz_*`` has a finite sample."""
        if self.reference is None:
            return np.zeros(4, bool)
        return np.any(np.isfinite(self.reference), axis=0)

    @property
    def travel_sensors(self) -> TravelSensors:
        """The travel sensor set (see :class:`TravelSensors`)."""
        count = int(self.travel_present.sum())
        return (TravelSensors.NONE, TravelSensors.ONE, TravelSensors.TWO,
                TravelSensors.DEAD_CORNER, TravelSensors.ALL)[count]  # fmt: skip

    def mode(self) -> str:
        """The sensor set in words, for summaries."""
        return sensor_mode(self.travel_present, self.az_assumed, self.speed_source)

    def input_flags(self) -> np.ndarray:
        """(n,) :class:`StepFlag` bits of inputs the log did not have."""
        bits = input_bits(self.az_assumed, self.speed_source)
        return np.full(len(self.t), bits, dtype=np.int64)

    @property
    def sample_rate(self) -> float:
        """Median sample rate [Hz] (of the IMU's own stamps, ``ax``'s, for channels on their
        own clocks)."""
        t = self.t[np.isfinite(self.acc[:, 0])] if self.own_clocks else self.t
        return float(1.0 / order_statistics.median(np.diff(t)))

    def to_frame(self) -> pd.DataFrame:
        """The signals as a DataFrame with the log's column names (no ``az`` where assumed)."""
        import pandas as pd

        columns = {"t": self.t, "vx": self.vx}
        # an assumed az (g, the log had none) is left out, so that it stays assumed
        kept = ("ax", "ay") if self.az_assumed else ("ax", "ay", "az")
        columns.update(zip(kept, self.acc.T))
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
        if self.steer is not None:
            columns[STEER] = self.steer
        for names, values in (
            (SPIN, self.spin),
            (TORQUE, self.torque),
            (REFERENCE_FX, self.reference_fx),
            (REFERENCE_FY, self.reference_fy),
        ):
            if values is not None:
                columns.update(zip(names, values.T))  # fmt: skip
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
            az_assumed=self.az_assumed,
            speed_source=self.speed_source,
            travel_quantum=self.travel_quantum,
            spin=cut(self.spin),
            torque=cut(self.torque),
            steer=cut(self.steer),
            reference_fx=cut(self.reference_fx),
            reference_fy=cut(self.reference_fy),
            own_clocks=self.own_clocks,
        )


def check_time_column(t: np.ndarray, source: str) -> Steps:
    """A log's time column: finite, increasing, in seconds (one-line :class:`LogError`);
    its :class:`Steps`."""
    _check_time(t, source)
    steps = Steps.of(t)
    if steps.median > MAX_SAMPLE_INTERVAL:
        raise LogError(
            f"{source}: column 't' advances by {steps.median:.4g} per sample: more than "
            f"{MAX_SAMPLE_INTERVAL} s, it looks like milliseconds (give seconds)"
        )
    return steps


#: Time stamps per block of a pass over a time column (which may be on disk).
TIME_BLOCK = 1 << 16


def step_blocks(t: np.ndarray):
    """A pass over the steps ``t[k + 1] - t[k]``, ``(first k, steps)`` a block at a time,
    the pages of a column on disk dropped after each (:mod:`.spill`)."""

    def blocks():
        for start in range(0, t.size - 1, TIME_BLOCK):
            yield start, np.diff(t[start : start + TIME_BLOCK + 1])
            release(t)

    return blocks


def _check_time(t: np.ndarray, source: str) -> None:
    """Finite and increasing ``t``, else a one-line :class:`LogError` (the first missing
    stamp, then the first step back), a block at a time."""
    if t.size < 2:
        raise LogError(f"{source}: needs at least 2 samples, has {t.size}")
    for start in range(0, t.size, TIME_BLOCK):
        missing = np.flatnonzero(~np.isfinite(t[start : start + TIME_BLOCK]))
        if missing.size:
            row = start + missing[0]
            raise LogError(f"{source}: column 't' has no valid time stamp at row {row}")
    for start, steps in step_blocks(t)():
        bad = np.flatnonzero(steps <= 0.0)
        if bad.size:
            row = start + bad[0] + 1
            raise LogError(
                f"{source}: column 't' is not increasing at row {row} "
                f"(t = {t[row - 1]!r} then {t[row]!r})"
            )


#: A step longer than this many median intervals is a gap (a sample or more missing): the
#: log is split there into segments, each uniform on its own (:class:`Steps`).
GAP_RATIO = 1.5


@dataclass(frozen=True)
class Steps:
    r"""A log's sample intervals as the uniformity and sample-rate checks read them: their
    median :math:`m`, their largest deviation from it within the segments,
    :math:`\max_k |\Delta t_k - m|` over the steps :math:`\Delta t_k \le` :data:`GAP_RATIO`
    :math:`m`, and the gaps (the longer steps): their number and the longest.

    A gap (a logger pause, a dropped block of an MF4 clock group) splits the log into
    segments; the filters that need uniform steps restart after it (:class:`~wheelload.
    estimators.logs.signals.ChunkFilter`) rather than refuse the log.
    """

    median: float
    deviation: float
    gaps: int = 0
    longest_gap: float = 0.0

    @staticmethod
    def of(t: np.ndarray) -> Steps:
        """The steps of increasing time stamps ``t`` (at least 2), a block at a time: the
        median by exact selection (``np.median``'s number)."""
        blocks = step_blocks(t)
        steps = lambda: (values for _, values in blocks())  # noqa: E731
        median = float(order_statistics.blocked_median(steps, t.size - 1))
        limit = GAP_RATIO * median
        deviation, gaps, longest = 0.0, 0, 0.0
        for values in steps():
            gap = values > limit
            if np.any(~gap):
                deviation = max(deviation, float(np.max(np.abs(values[~gap] - median))))
            if np.any(gap):
                gaps += int(np.count_nonzero(gap))
                longest = max(longest, float(np.max(values[gap])))
        return Steps(median, deviation, gaps, longest)

    @property
    def gap(self) -> float:
        """The shortest step taken as a gap [s]."""
        return GAP_RATIO * self.median

    def uniform(self, tolerance: float = 0.05) -> bool:
        """Whether every step within a segment is within ``tolerance`` of the median."""
        return self.deviation <= tolerance * self.median


@dataclass(frozen=True, kw_only=True)
class Sample:
    """One sample of the signals used by the filter (SI units).

    ``rates`` (wx wy wz), ``rate_dots`` (their derivative) and ``hub``
    (az_fl .. az_rr) are optional; an absent group is missing (NaN) in
    :meth:`vector`, which drops the terms that need it.
    """

    d: np.ndarray  # (4,) travel
    v: np.ndarray  # (4,) travel rate
    acc: np.ndarray  # (3,) ax, ay, az specific force
    vx: float
    rates: np.ndarray | None = None  # (3,) wx, wy, wz body rates [rad/s], if logged
    rate_dots: np.ndarray | None = None  # (3,) their derivative [rad/s^2], if logged
    hub: np.ndarray | None = None  # (4,) az_fl..az_rr hub specific force, if logged
    # Tyre-force inputs (not in :meth:`vector`: the load estimators do not use them).
    spin: np.ndarray | None = None  # (4,) omega_fl..omega_rr [rad/s], if logged
    torque: np.ndarray | None = None  # (4,) torque_fl..torque_rr [N m], if logged
    steer: float | None = None  # front road-wheel angle [rad], if logged

    def vector(self) -> np.ndarray:
        def given(values: np.ndarray | None, size: int) -> np.ndarray:
            return np.full(size, np.nan) if values is None else np.asarray(values, float)

        return np.concatenate(
            [
                self.d,
                self.v,
                self.acc,
                [self.vx],
                given(self.rates, 3),
                given(self.rate_dots, 3),
                given(self.hub, 4),
            ]
        ).astype(float)

    def parts(self) -> tuple[tuple[np.ndarray | float | None, int], ...]:
        """``(values, size)`` per group in :meth:`vector` order; None for an absent group."""
        return (
            (self.d, 4),
            (self.v, 4),
            (self.acc, 3),
            ((self.vx,), 1),
            (self.rates, 3),
            (self.rate_dots, 3),
            (self.hub, 4),
        )
