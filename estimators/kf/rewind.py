"""Time-stamped measurements for the two-stage KF: each at its own time, a late one by rewind.

A measurement is a time stamp :math:`t` [s] and the channels it carries (an input vector in
``wheelload.models.INPUTS`` order, NaN where the measurement has no value). The filter predicts
from the time of its state :math:`T` to :math:`t` (:math:`dt = t - T`) and updates with the
rows the carried channels inform: the step's own masks skip exactly the rows whose inputs are
absent (``models/input_validity.py``), so a travel frame updates the four suspension rows and a
specific-force frame the three equilibrium rows.

A measurement older than the state (:math:`t \\le T`: a channel's latency, or a frame out of
order) rewinds: the filter keeps a fixed ring of the last :data:`DEFAULT_CHECKPOINTS`
measurements, each with the state before it (a checkpoint); the late one is inserted in time
order (merged into a measurement of the same time stamp, its channels replacing those there),
the state of the checkpoint it falls after is restored and every measurement from there on is
filtered again. The result is that of the measurements fed in time order (rednose's rewind and
replay, Panjkovic's "out-of-sequence measurements" by reprocessing). A measurement older than
``max_rewind_age`` behind the state, or older than the ring's oldest measurement once the ring
is full, is dropped, flagged :attr:`StepFlag.MEASUREMENT_TOO_OLD` and counted.

Speed is context, not a measurement: the equilibrium rows need ``vx`` (aerodynamic lift), which
a CAN car sends in its own slower frame. A measurement without ``vx`` takes the last one at or
before its time stamp, at most ``speed_hold`` old (held in the checkpoints, so a replay holds
as the time-ordered feed does).

The rows come faster than any one channel (two frames may lie microseconds apart), so the
step's refusal of an interval below ``sample_interval / interval_band`` (``INTERVAL_SHORT``)
would drop measurements: the filter runs with ``interval_band`` :data:`TIMED_INTERVAL_BAND`
(no refusal); the measurement noise follows the fixed nominal interval (the filter's
``sample_interval``). Every channel on every row, in order,
gives the synchronous filter's numbers.

The generated C has the same semantics (``PREFIX_step_at``, ``estimators/codegen``).

Example
-------
>>> timed = kf.timed(max_rewind_age=0.1)
>>> estimate = timed.update_at(t, u)  # u: INPUTS order, NaN where absent
>>> timed.dropped, timed.rewinds
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS

#: Checkpoints (measurements with the state before each) the ring keeps, Python and C.
DEFAULT_CHECKPOINTS = 64
#: Oldest a measurement may be behind the filter's state [s].
DEFAULT_MAX_REWIND_AGE = 0.5
#: Longest a speed holds for measurements without one [s].
DEFAULT_SPEED_HOLD = 1.0
#: ``interval_band`` of the timed filter: no interval is refused as short (nor flagged long).
#: Outside the band's domain for a file (1e3), finite in float.
TIMED_INTERVAL_BAND = 1e30

_SPEED = INPUTS.index("vx")
_BAND = TUNING.index("interval_band")


@dataclass(frozen=True, kw_only=True)
class RewindSettings:
    """The ring's size, the oldest a measurement may be, and the speed's hold [s]."""

    checkpoints: int = DEFAULT_CHECKPOINTS
    max_rewind_age: float = DEFAULT_MAX_REWIND_AGE
    speed_hold: float = DEFAULT_SPEED_HOLD

    def __post_init__(self) -> None:
        if not 1 <= self.checkpoints <= 1 << 16:
            raise ValueError(f"checkpoints must be 1 to 65536, got {self.checkpoints}")
        for name in ("max_rewind_age", "speed_hold"):
            value = getattr(self, name)
            if not 0.0 <= value < float("inf"):
                raise ValueError(f"{name} must be >= 0 s and finite, got {value}")


def timed_tuning(tuning: np.ndarray) -> np.ndarray:
    """``tuning`` with :data:`TIMED_INTERVAL_BAND` (a copy)."""
    tuning = np.array(tuning, float)
    tuning[_BAND] = TIMED_INTERVAL_BAND
    return tuning


class TimedFilter:
    """The two-stage KF fed time-stamped measurements, late ones by rewind and replay.

    Built by :meth:`TwoStageKF.timed`. :meth:`update_at` takes one measurement; the state
    after it (the newest time stamp's) is :attr:`loads`, :attr:`std`, :attr:`time`.
    ``on_output(index, t, x, std, flags)`` (optional) is called after every step, a replayed
    one too, with the measurement's number (its order of arrival).
    """

    def __init__(self, live, settings: RewindSettings, first_interval: float, on_output=None):
        self._live = live
        self.settings = settings
        self.first_interval = float(first_interval)
        size = settings.checkpoints
        self._state = live.state_view()  # x, P, m in the compiled step's buffer
        n_state = self._state.size
        self._std = np.full(4, np.nan)
        self._ring_t = np.zeros(size)
        self._ring_u = np.zeros((size, len(INPUTS)))
        self._ring_before = np.zeros((size, n_state))
        self._ring_t_before = np.zeros(size)  # NaN: the initial state
        self._ring_hold = np.zeros((size, 2))  # speed held before and its time (NaN: none)
        self._ring_index = np.zeros(size, np.int64)
        self._count = 0
        self.time = np.nan
        self._hold = np.array([np.nan, np.nan])
        self.flags = 0
        self.dropped = 0
        self.rewinds = 0
        self.replayed = 0
        self._arrivals = 0
        self._on_output = on_output

    @property
    def loads(self) -> np.ndarray:
        """The loads at :attr:`time` [N] (a copy)."""
        return self._state[:4].copy()

    @property
    def std(self) -> np.ndarray:
        """Their standard deviations [N] (from the last step; a copy)."""
        return self._std.copy()

    def update_at(self, t: float, u: np.ndarray) -> int:
        """One measurement at time stamp ``t`` [s], channels ``u`` (INPUTS order, NaN absent).

        Returns the step flags of the newest measurement after it, or
        :attr:`StepFlag.MEASUREMENT_TOO_OLD` alone for a dropped one (state unchanged).
        """
        index = self._arrivals
        self._arrivals += 1
        u = np.asarray(u, float)
        if u.shape != (len(INPUTS),):
            raise ValueError(f"a measurement has {len(INPUTS)} channels, got shape {u.shape}")
        if not np.isfinite(t):
            self.dropped += 1
            return int(StepFlag.MEASUREMENT_TOO_OLD)
        n, size = self._count, self.settings.checkpoints
        if n == 0 or t > self.time:
            if n == size:
                self._evict()
                n -= 1
            self._insert(n, t, u, index)
            self._replay(n)
            return self.flags
        if t < self.time - self.settings.max_rewind_age:
            self.dropped += 1
            return int(StepFlag.MEASUREMENT_TOO_OLD)
        position = int(np.searchsorted(self._ring_t[:n], t, side="left"))
        if self._ring_t[position] == t:
            merged = self._ring_u[position]
            present = np.isfinite(u)
            merged[present] = u[present]
        elif position == 0 and n == size:
            self.dropped += 1
            return int(StepFlag.MEASUREMENT_TOO_OLD)
        else:
            if n == size:
                self._evict()
                position -= 1
            self._insert(position, t, u, index)
        self.rewinds += 1
        self._replay(position)
        return self.flags

    def _evict(self) -> None:
        """Drop the oldest checkpoint (its successor's keeps the state before that)."""
        n = self._count
        for ring in (self._ring_t, self._ring_u, self._ring_before, self._ring_t_before,
                     self._ring_hold, self._ring_index):  # fmt: skip
            ring[: n - 1] = ring[1:n]
        self._count = n - 1

    def _insert(self, position: int, t: float, u: np.ndarray, index: int) -> None:
        """Open slot ``position`` for the measurement; its checkpoint is set by the replay."""
        n = self._count
        for ring in (self._ring_t, self._ring_u, self._ring_before, self._ring_t_before,
                     self._ring_hold, self._ring_index):  # fmt: skip
            ring[position + 1 : n + 1] = ring[position:n]
        self._ring_t[position] = t
        self._ring_u[position] = u
        self._ring_index[position] = index
        if position == n:  # the newest: the state before it is the current one
            self._ring_before[position] = self._state
            self._ring_t_before[position] = self.time
            self._ring_hold[position] = self._hold
        else:  # before a later one: the state before that one is the state before this
            self._ring_before[position] = self._ring_before[position + 1]
            self._ring_t_before[position] = self._ring_t_before[position + 1]
            self._ring_hold[position] = self._ring_hold[position + 1]
        self._count = n + 1

    def _replay(self, start: int) -> None:
        """Restore the checkpoint of measurement ``start`` and filter it and all after it."""
        live = self._live
        self._state[:] = self._ring_before[start]
        time = self._ring_t_before[start]
        hold = self._ring_hold[start].copy()
        speed_hold = self.settings.speed_hold
        for k in range(start, self._count):
            if k > start:
                self._ring_before[k] = self._state
                self._ring_t_before[k] = time
                self._ring_hold[k] = hold
                self.replayed += 1
            t = self._ring_t[k]
            u = self._ring_u[k]
            if np.isfinite(u[_SPEED]):
                hold[:] = (u[_SPEED], t)
            elif np.isfinite(hold[1]) and t - hold[1] <= speed_hold:
                u = u.copy()
                u[_SPEED] = hold[0]
            dt = self.first_interval if np.isnan(time) else t - time
            estimate = live.update_inputs(u, dt)
            self.flags = estimate.flags
            self._std[:] = estimate.std
            time = t
            if self._on_output is not None:
                self._on_output(int(self._ring_index[k]), t, self._state[:4], self._std,
                                self.flags)  # fmt: skip
        self.time = time
        self._hold = hold


def latency_vector(latency) -> np.ndarray:
    """Each input's latency [s] (INPUTS order) from None (all 0), a vector, or a mapping of
    channel names to seconds (the channels not named: 0)."""
    if latency is None:
        return np.zeros(len(INPUTS))
    if isinstance(latency, Mapping):
        unknown = sorted(set(latency) - set(INPUTS))
        if unknown:
            raise ValueError(
                f"latency: no input channel {', '.join(unknown)}; the channels are {INPUTS}"
            )
        latency = [float(latency.get(name, 0.0)) for name in INPUTS]
    latency = np.asarray(latency, float)
    if latency.shape != (len(INPUTS),) or not np.all(np.isfinite(latency) & (latency >= 0)):
        raise ValueError(f"latency: one value >= 0 s per channel of {INPUTS}")
    return latency


def measurements(t: np.ndarray, inputs: np.ndarray, latency=None):
    """A long table's rows as measurements in order of arrival: ``(stamps, channels)``
    (:func:`measurement_rows` without the rows)."""
    stamps, channels, _ = measurement_rows(t, inputs, latency)
    return stamps, channels


def measurement_rows(t: np.ndarray, inputs: np.ndarray, latency=None):
    """A long table's rows as measurements in order of arrival: ``(stamps, channels, rows)``,
    ``rows`` the row of the table each measurement comes from.

    ``t`` (n,) the times the rows were logged (their arrival, in row order, not necessarily
    increasing); ``inputs`` (n, INPUTS) NaN where a channel has no new value; ``latency``
    [s] per channel (:func:`latency_vector`: a vector, a mapping of names, or None for 0): a
    value logged at ``t`` was measured at
    ``t - latency``. The channels of one row with one latency form one measurement; within a
    row the most delayed come first. Rows without a value are left out.
    """
    t = np.asarray(t, float)
    inputs = np.asarray(inputs, float)
    latency = latency_vector(latency)
    groups = [latency == value for value in np.unique(latency)[::-1]]
    stamps, channels, rows = [], [], []
    for k in range(t.size):
        row = inputs[k]
        present = np.isfinite(row)
        for group in groups:
            here = group & present
            if here.any():
                u = np.full(len(INPUTS), np.nan)
                u[here] = row[here]
                stamps.append(t[k] - latency[group][0])
                channels.append(u)
                rows.append(k)
    return (np.array(stamps), np.array(channels).reshape(-1, len(INPUTS)),
            np.array(rows, np.int64))  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class TimedRun:
    """A whole log through :class:`TimedFilter`.

    Per measurement in order of arrival (``stamps`` (n,) [s]): ``arrival_loads`` (n, 4) [N]
    and ``arrival_time`` (n,), the state right after it arrived (its newest time stamp; what
    a running filter shows), ``arrival_flags`` (n,); ``loads``, ``std`` (n, 4) and ``flags``
    (n,) the estimate at the measurement's own time stamp after the last replay that
    included it (NaN loads and :attr:`StepFlag.MEASUREMENT_TOO_OLD` for a dropped one);
    ``dropped`` and ``rewinds`` counted.
    """

    stamps: np.ndarray
    arrival_time: np.ndarray
    arrival_loads: np.ndarray
    arrival_flags: np.ndarray
    loads: np.ndarray
    std: np.ndarray
    flags: np.ndarray
    dropped: int
    rewinds: int
    replayed: int


def run_timed(
    make_filter, stamps: np.ndarray, channels: np.ndarray, input_flags: np.ndarray | None = None
) -> TimedRun:
    """Feed the measurements ``(stamps, channels)`` in order to ``make_filter(on_output)``;
    ``input_flags`` (n,) :class:`StepFlag` bits of inputs the log did not have (``Signals.
    input_flags()`` of each measurement's row), ORed into its flags as ``run`` does."""
    n = stamps.size
    loads = np.full((n, 4), np.nan)
    std = np.full((n, 4), np.nan)
    flags = np.full(n, int(StepFlag.MEASUREMENT_TOO_OLD), np.int64)

    def record(index, _t, x, s, step_flags):
        loads[index] = x
        std[index] = s
        flags[index] = step_flags

    timed = make_filter(record)
    arrival_time = np.empty(n)
    arrival_loads = np.empty((n, 4))
    arrival_flags = np.empty(n, np.int64)
    for k in range(n):
        arrival_flags[k] = timed.update_at(stamps[k], channels[k])
        arrival_time[k] = timed.time
        arrival_loads[k] = timed._state[:4]
    if input_flags is not None:
        arrival_flags |= input_flags
        flags |= input_flags
    return TimedRun(
        stamps=stamps, arrival_time=arrival_time, arrival_loads=arrival_loads,
        arrival_flags=arrival_flags, loads=loads, std=std, flags=flags,
        dropped=timed.dropped, rewinds=timed.rewinds, replayed=timed.replayed,
    )  # fmt: skip
