"""The two-stage KF over a log file in chunks: memory bounded by the chunk, not the log.

The lean whole-log path of ``wheelload estimate``
(``estimators/logs/readers/chunks.py``: Parquet record batches, CSV blocks):

1. :class:`LogScan` takes the chunks and keeps what the whole-log checks
   need: the time column (8 bytes a sample: the nominal interval, the time and
   sample-rate checks, the differentiators' uniformity check), the median of
   ``az`` (unit check; freed after it), the channels' peaks and which
   channels have a finite sample, the first :data:`~log_checks.WINDOW` s of
   motion (wiring checks, exactly the window :func:`check_wiring` examines on
   the whole log) and the first seconds (still period). :func:`scan_log` reads
   the whole log through it.
2. :meth:`LogStream.chunks` runs the filter's
   :class:`~wheelload.estimators.loops.compiled.ColumnLoop` on the chunks' column arrays
   (validity, sample interval and ``uint32`` status bits computed in C; no
   stacked copies), the filter state and the differentiators' state carried
   from chunk to chunk, so the loads equal ``TwoStageKF.run`` on the whole log
   to the bit: the chunks read again after :func:`scan_log`, or, handed as
   ``source``, the chunks a :class:`LogScan` takes as they are read (the log read
   once: its time column first, :mod:`~wheelload.studies.pipeline.lean_estimate`).

A log this path cannot read as plain numbers raises
:class:`~wheelload.estimators.logs.readers.chunks.ChunkError` before any output,
and the caller reads it the ordinary way (whose errors name the row).

Example
-------
>>> stream = scan_log(Path("drive.parquet"), kf)
>>> for chunk in stream.chunks():
...     writer.write(chunk.columns())
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators.guards import settings as guard
from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.kf.step_cache import N_CARRIED, STEP_FUNCTION, STEP_OUTPUT_NAMES
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import FAULT_MARGIN, TwoStageKF, about_faults
from wheelload.estimators.logs.checks import MOVING, WINDOW, check_wiring
from wheelload.estimators.logs.model_error import (
    MAX_SAMPLES,
    NOTHING,
    Diagnosis,
    diagnose_inputs,
)
from wheelload.estimators.logs.readers.chunks import (
    PARQUET_ROWS,
    ChunkError,
    chunk_columns,
    read_chunks,
)
from wheelload.estimators.logs.signals import (
    DEFAULT_RATE_FILTER,
    VELOCITY_CUTOFF,
    Differentiator,
    RateDerivativeFilter,
    RateEstimator,
    check_units,
    say_gaps,
)
from wheelload.estimators.loops.compiled import ColumnLayout, ColumnLoop, FlagRule
from wheelload.estimators.result import MASS_PROPERTY_COLUMNS, RESIDUALS, SensorFault, StepFlag
from wheelload.estimators.types import (
    HUB,
    RATE_DERIVATIVES,
    RATES,
    REFERENCE,
    REQUIRED,
    TRAVEL,
    TRAVEL_RATE,
    WHEEL_SPEED,
    LogError,
    Signals,
    SpeedSource,
    Steps,
    check_time_column,
    input_bits,
    sensor_mode,
)
from wheelload.models import GRAVITY, INPUTS
from wheelload.models.conventions import WHEELS
from wheelload.models.input_validity import MAX_INTERVAL
from wheelload.models.runtime.spill import Appended, release

GROUPS = (TRAVEL, TRAVEL_RATE, RATES, HUB, RATE_DERIVATIVES)
#: Output columns of the loop: loads, their std, residual, then the fault monitor's.
LOOP_COLUMNS = (
    "x_next", "std", "residual", "fault", "fault_statistic", "mass_properties",
    "mass_properties_std",
)  # fmt: skip
#: The first block row of the mass properties (after loads, std, residual, 2 x 7 monitor).
_MASS_ROW = 4 + 4 + 3 + 7 + 7


@dataclass(frozen=True, kw_only=True, eq=False)
class EstimateChunk:
    """Consecutive samples of the estimates; ``block`` rows: loads 0-3, std 4-7, residual 8-10.

    ``reference`` is the log's ``fz_*`` (NaN where absent), or None without any.
    """

    t: np.ndarray
    block: np.ndarray  # (11+, n) one contiguous row per output column
    flags: np.ndarray  # (n,) uint32
    reference: np.ndarray | None  # (n, 4)

    @property
    def loads(self) -> np.ndarray:
        return self.block[0:4].T

    @property
    def std(self) -> np.ndarray:
        return self.block[4:8].T

    @property
    def residual(self) -> np.ndarray:
        return self.block[8:11].T

    @property
    def mass_properties(self) -> np.ndarray:
        """The online mass properties (n, 4) and, after them, their std (n, 4): (n, 8)."""
        return self.block[_MASS_ROW : _MASS_ROW + 8].T

    def columns(self) -> dict[str, np.ndarray]:
        """The columns of ``Estimate.to_pandas`` (with std), by name."""
        columns = {"t": self.t}
        columns.update({f"fz_{w}": self.block[i] for i, w in enumerate(WHEELS)})
        columns.update({f"fz_std_{w}": self.block[4 + i] for i, w in enumerate(WHEELS)})
        columns.update({name: self.block[8 + i] for i, name in enumerate(RESIDUALS)})
        columns.update(
            {name: self.block[_MASS_ROW + i] for i, name in enumerate(MASS_PROPERTY_COLUMNS)}
        )
        columns["status"] = self.flags
        return columns


@dataclass(frozen=True, kw_only=True)
class ChannelStats:
    """Per-wheel statistics of the travel and travel-rate channels (log warnings)."""

    travel_count: np.ndarray  # finite samples of d_*
    travel_peak: np.ndarray  # max |d_*| over them
    rate_count: np.ndarray  # finite samples of v_* (logged)
    rate_min: np.ndarray
    rate_max: np.ndarray


def _column_peak(values: np.ndarray) -> np.ndarray:
    return np.nanmax(np.abs(values), axis=0, initial=0.0)


class _Head:
    """Samples collected while ``keep(t)`` holds, from a start chosen by ``begin``."""

    def __init__(self) -> None:
        self.parts: dict[str, list[np.ndarray]] = {}
        self.done = False

    def add(self, chunk: dict[str, np.ndarray], start: int, stop: int) -> None:
        for name, values in chunk.items():
            self.parts.setdefault(name, []).append(values[start:stop])

    def array(self, name: str) -> np.ndarray:
        return np.concatenate(self.parts[name])


def _speed(chunk: dict[str, np.ndarray], n: int) -> tuple[np.ndarray, SpeedSource]:
    """``vx`` as :func:`signals_from_frame` makes it (logged, wheel-speed mean, or 0)."""
    if "vx" in chunk:
        return chunk["vx"], SpeedSource.LOGGED
    wheels = [chunk[name] for name in WHEEL_SPEED if name in chunk]
    if wheels:
        stacked = np.column_stack(wheels)
        finite = np.isfinite(stacked)
        count = finite.sum(axis=1)
        total = np.where(finite, stacked, 0.0).sum(axis=1)
        return np.where(count > 0, total / np.maximum(count, 1), np.nan), SpeedSource.WHEEL_SPEEDS
    return np.zeros(n), SpeedSource.NONE


def _travel(chunk: dict[str, np.ndarray], n: int) -> np.ndarray:
    if TRAVEL[0] in chunk:
        return np.column_stack([chunk[name] for name in TRAVEL])
    return np.full((n, 4), np.nan)


@dataclass(frozen=True, kw_only=True, eq=False)
class LogStream:
    """A scanned log (see module docstring): its facts and :meth:`chunks` of estimates."""

    path: Path
    source: str
    names: tuple[str, ...]  # our columns present in the file
    t: np.ndarray  # on disk for a long log (:mod:`~wheelload.models.runtime.spill`)
    steps: Steps  # the sample intervals' median and largest deviation
    travel_present: np.ndarray  # (4,) bool
    reference_present: np.ndarray | None  # (4,) bool, None: no fz_* column
    velocities_derived: bool
    az_assumed: bool
    speed_source: SpeedSource
    channel_stats: ChannelStats
    wiring: Signals | None  # the first WINDOW s of motion, None if never moving
    head: Signals  # the first samples (still period)
    rows: int  # rows per chunk

    def __len__(self) -> int:
        return len(self.t)

    @property
    def sample_rate(self) -> float:
        """Median sample rate [Hz]."""
        return float(1.0 / self.steps.median)

    def mode(self) -> str:
        """The sensor set in words (as :meth:`Signals.mode`)."""
        return sensor_mode(self.travel_present, self.az_assumed, self.speed_source)

    def filter_facts(self) -> tuple:
        """What the filter takes of the whole log (:meth:`chunks`): the nominal sample
        interval, the steps' median and uniformity, the channels present, the speed's
        source. The nominal interval is the steps' median where every step is below
        :data:`~wheelload.models.input_validity.MAX_INTERVAL` (the same steps: no second
        pass over the time stamps)."""
        steps = self.steps
        every_step = steps.median + steps.deviation < 0.5 * MAX_INTERVAL
        reference = self.reference_present
        return (
            steps.median if every_step else nominal_interval(self.t),
            steps.median,
            steps.uniform(),
            tuple(self.travel_present.tolist()),
            None if reference is None else tuple(reference.tolist()),
            self.velocities_derived,
            self.az_assumed,
            self.speed_source,
        )

    def wiring_report(self):
        """:func:`check_wiring` on the log (its first WINDOW s of motion)."""
        if self.wiring is None:
            return check_wiring(self.t[:2], np.zeros(2), np.zeros((2, 3)), np.zeros((2, 4)))
        w = self.wiring
        return check_wiring(w.t, w.vx, w.acc, w.d, w.rates)

    def chunks(
        self,
        kf: TwoStageKF,
        *,
        faults: list[SensorFault] | None = None,
        diagnosis: Diagnosis | None = None,
        source: Iterable[dict[str, np.ndarray]] | None = None,
        thinned: ThinnedInputs | None = None,
    ) -> Iterator[EstimateChunk]:
        """The estimates, chunk by chunk; ``faults`` receives the isolated sensor faults.
        With a file check's ``diagnosis`` (:mod:`~wheelload.estimators.logs.model_error`) its
        travel zero is taken off and its file parameter widens σ, as in ``TwoStageKF.run``.
        ``source``: the log's chunks as read (:meth:`signal_chunks`); ``thinned`` takes
        the inputs the file check reads (:meth:`file_check`)."""
        loop = filter_loop(kf)
        state0 = kf.initial_state()
        state = [np.ascontiguousarray(np.ravel(a, order="F"), dtype=float)
                 for a in (state0.x, state0.P, state0.m)]  # fmt: skip
        tuning = kf.tuning_for(kf.sample_interval or nominal_interval(self.t))
        base = input_bits(self.az_assumed, self.speed_source)
        tracker = _FaultTracker()
        start, last = 0, 0.0
        rate_filter = RateDerivativeFilter.of(kf.vehicle)
        for t, columns in self.signal_chunks(source=source, rate_filter=rate_filter):
            n = len(t)
            if thinned is not None:
                thinned.add(t, columns)
            if diagnosis is not None and np.any(diagnosis.travel_zero):
                columns = {**columns, **{name: columns[name] - diagnosis.travel_zero[i]
                                         for i, name in enumerate(TRAVEL)}}  # fmt: skip
            values = [columns.get(name) for name in INPUTS]
            block = np.empty((loop.n_columns, n))
            flags = np.empty(n, dtype=np.uint32)
            dt_first = float(t[1] - t[0]) if start == 0 else float(t[0] - last)
            last = t[-1]
            loop(state, [kf.p, tuning], values, t, dt_first, list(block), flags, base)
            tracker.add(t, block[11:18], block[18:25])
            if diagnosis is not None and diagnosis.change is not None:
                change = diagnosis.load_change(_input_rows(columns, n))
                block[4:8] = np.sqrt(block[4:8] ** 2 + change.T**2)
            reference = None
            if self.reference_present is not None:
                reference = np.column_stack(
                    [columns[name] if name in columns else np.full(n, np.nan) for name in REFERENCE]
                )
            start += n
            yield EstimateChunk(t=t, block=block, flags=flags, reference=reference)
        if faults is not None:
            faults.extend(tracker.finish())

    def file_check(
        self,
        vehicle,
        faults,
        mass_properties: np.ndarray | None,
        *,
        static_given: bool,
        thinned: ThinnedInputs | None = None,
    ) -> Diagnosis:
        """The file check of ``TwoStageKF.run`` on this log, read in chunks: every k-th
        sample (:data:`~wheelload.estimators.logs.model_error.MAX_SAMPLES` at most), the
        samples about the ``faults`` isolated left out, the car as ``mass_properties``
        (the payload estimate's at the end) found it; the travel zeros are known when
        static loads were given. ``thinned``: those samples, taken while the log was
        estimated (:meth:`chunks`), else read here."""
        if len(self) == 0:
            return NOTHING
        rate_filter = RateDerivativeFilter.of(vehicle)
        t, inputs = (thinned or self.thinned_inputs(MAX_SAMPLES, rate_filter)).result()
        return diagnose_inputs(
            inputs,
            vehicle,
            about_faults(t, faults, FAULT_MARGIN),
            travel_zero=not static_given,
            mass_properties=mass_properties,
        )

    def thinned_inputs(
        self, most: int, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
    ) -> ThinnedInputs:
        """The whole log's inputs as the file check reads them (:class:`ThinnedInputs`),
        without holding it (the body-rate derivatives from ``rate_filter``)."""
        thinned = ThinnedInputs(most)
        for t, columns in self.signal_chunks(rate_filter=rate_filter):
            thinned.add(t, columns)
        return thinned

    def signal_chunks(
        self,
        extra: tuple[str, ...] = (),
        source: Iterable[dict[str, np.ndarray]] | None = None,
        rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER,
    ) -> Iterator[tuple[np.ndarray, dict[str, np.ndarray]]]:
        """The log's signals chunk by chunk, ``(t, {name: values})``, as the whole-log reader
        makes them: the columns read (ours and ``extra``, other columns of the file), the
        travel rates and body-rate derivatives derived where not logged (their filters'
        state carried, so each equals the whole log's to the bit; the derivatives left out
        where the time stamps are too irregular for them), ``az`` where assumed (g) and
        ``vx`` (logged, the wheel speeds' mean, or 0). ``source``: the chunks of our
        columns as read (:class:`LogScan`), instead of reading the file again."""
        travel_rates = (
            Differentiator(self.steps, 4, VELOCITY_CUTOFF, self.source)
            if self.velocities_derived
            else None
        )
        rate_dots = None
        # Derived whatever the [model] switches: the fault monitor's parity test uses every
        # term the inputs allow (as the whole-log path, estimators/logs/signals.py).
        if RATE_DERIVATIVES[0] not in self.names and RATES[0] in self.names:
            try:
                rate_dots = RateEstimator(self.steps, 3, self.source, rate_filter)
            except LogError:
                rate_dots = None  # too irregular: the terms that need them are dropped
        names = list(self.names) + [name for name in extra if name not in self.names]
        start = 0
        read = source is None
        for chunk in read_chunks(self.path, names, rows=self.rows) if read else source:
            n = len(chunk["t"])
            if n == 0:
                continue
            t = chunk["t"]
            if read:
                same = np.array_equal(self.t[start : start + n], t)
                release(self.t)
                if not same:
                    raise LogError(f"{self.source}: changed while it was read: read it again")
            columns = dict(chunk)
            if travel_rates is not None:
                derived = travel_rates(_travel(chunk, n), t)
                columns.update({name: derived[:, i] for i, name in enumerate(TRAVEL_RATE)})
            if self.az_assumed:
                columns["az"] = np.broadcast_to(np.float64(GRAVITY), (n,))
            columns["vx"] = _speed(chunk, n)[0]
            if rate_dots is not None:
                derived = rate_dots(np.column_stack([chunk[name] for name in RATES]), t)
                columns.update({name: derived[:, i] for i, name in enumerate(RATE_DERIVATIVES)})
            start += n
            yield t, columns
        if read and start != len(self.t):
            raise LogError(f"{self.source}: changed while it was read: read it again")


class ThinnedInputs:
    """Every k-th sample's time and inputs (:data:`INPUTS` x m) of the samples taken, k
    the largest power of two up to ``n // most`` (at least 1) for the ``n`` taken: between
    ``most`` and ``4 most`` samples of a long log. Taken in one pass: k doubles as ``n``
    grows and the samples off the new k are dropped."""

    def __init__(self, most: int) -> None:
        self.most, self.step, self.count = most, 1, 0
        self.index: list[np.ndarray] = []
        self.times: list[np.ndarray] = []
        self.blocks: list[np.ndarray] = []

    def add(self, t: np.ndarray, columns: dict[str, np.ndarray]) -> None:
        """The next samples: their times (n,), their signals by name (as :meth:`signal_chunks`)."""
        n = len(t)
        keep = np.arange((-self.count) % self.step, n, self.step)
        self.index.append(self.count + keep)
        self.times.append(t[keep])
        kept = {name: np.broadcast_to(columns[name], (n,))[keep]
                for name in INPUTS if name in columns}  # fmt: skip
        self.blocks.append(_input_rows(kept, keep.size))
        self.count += len(t)
        if self.count // self.most >= 2 * self.step:
            while self.count // self.most >= 2 * self.step:
                self.step *= 2
            index = np.concatenate(self.index)
            kept = index % self.step == 0
            self.index = [index[kept]]
            self.times = [np.concatenate(self.times)[kept]]
            self.blocks = [np.hstack(self.blocks)[:, kept]]

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """The kept samples' times (m,) and inputs (INPUTS x m)."""
        if not self.times:
            return np.zeros(0), np.zeros((len(INPUTS), 0))
        return np.concatenate(self.times), np.hstack(self.blocks)


def _input_rows(columns: dict[str, np.ndarray], n: int) -> np.ndarray:
    """A chunk's inputs as the models take them (:data:`INPUTS` x n; NaN where absent)."""
    return np.vstack(
        [np.broadcast_to(columns[name], (n,)) if name in columns else np.full(n, np.nan)
         for name in INPUTS]
    )  # fmt: skip


class _FaultTracker:
    """:func:`~wheelload.estimators.kf.two_stage.sensor_faults` over consecutive chunks.

    An interval still on at the end of a chunk stays open (start, peak, last time).
    """

    def __init__(self) -> None:
        self.open: list[tuple[float, float, float] | None] = [None] * len(guard.FAULT_CHANNELS)
        self.closed: list[list[SensorFault]] = [[] for _ in guard.FAULT_CHANNELS]

    def add(self, t: np.ndarray, fault: np.ndarray, statistic: np.ndarray) -> None:
        n = len(t)
        for j, channel in enumerate(guard.FAULT_CHANNELS):
            on = fault[j] > 0.5
            carried = self.open[j]
            if carried is not None and not on[0]:
                self.closed[j].append(_fault(channel, carried[0], carried[2], carried[1]))
                carried = None
            self.open[j] = None
            if not on.any():
                continue
            edges = np.concatenate([[False], on, [False]])
            starts = np.flatnonzero(edges[1:] & ~edges[:-1])
            ends = np.flatnonzero(~edges[1:] & edges[:-1])
            for s, e in zip(starts, ends, strict=True):
                peak = float(np.max(statistic[j, s:e]))
                begun = float(t[s])
                if s == 0 and carried is not None:
                    begun, peak = carried[0], float(np.max([carried[1], peak]))
                if e == n:
                    self.open[j] = (begun, peak, float(t[n - 1]))
                else:
                    self.closed[j].append(_fault(channel, begun, float(t[e - 1]), peak))

    def finish(self) -> list[SensorFault]:
        rows = []
        for j, channel in enumerate(guard.FAULT_CHANNELS):
            rows += self.closed[j]
            carried = self.open[j]
            if carried is not None:
                rows.append(_fault(channel, carried[0], carried[2], carried[1]))
        return sorted(rows, key=lambda fault: fault.start)


def _fault(channel: str, start: float, end: float, statistic: float) -> SensorFault:
    return SensorFault(channel=channel, start=start, end=end, statistic=statistic)


def filter_loop(kf: TwoStageKF) -> ColumnLoop:
    """The column loop of ``kf``'s step: for the default step the stored loop (read
    without CasADi once built, :meth:`ColumnLoop.stored`), else :func:`column_loop`."""
    if kf.default_step:
        return _stored_loop()
    return column_loop(kf.step_function)


def _layout(used: int) -> ColumnLayout:
    """Loads, their std, residuals and the monitor's columns; the status bits of
    ``TwoStageKF.run`` (``used``: the entries of the step's ``used`` output)."""
    update = StepFlag.update_flags()
    rules = [FlagRule(output="used", element=i, below=True, bit=int(flag))
             for i, flag in enumerate(update[:used])]  # fmt: skip
    rules += [FlagRule(output="status", element=i, below=False, bit=int(flag))
              for i, flag in enumerate(StepFlag.guard_flags())]  # fmt: skip
    return ColumnLayout(
        n_accum=N_CARRIED,
        values="u",
        validity="u_valid",
        interval="dt",
        columns=LOOP_COLUMNS,
        rules=tuple(rules),
    )


@functools.cache
def _stored_loop() -> ColumnLoop:
    """The default step's loop; its ``used`` output has :data:`UPDATE_ROWS` and the model
    terms' dropped entries (every flag :meth:`StepFlag.update_flags` names)."""
    return ColumnLoop.stored(STEP_FUNCTION, _layout(len(StepFlag.update_flags())))


@functools.lru_cache(maxsize=4)
def column_loop(step) -> ColumnLoop:
    """The filter step over column arrays, with the status bits of ``TwoStageKF.run``."""
    return ColumnLoop(step, _layout(step.nnz_out(STEP_OUTPUT_NAMES.index("used"))))


def scan_log(
    path: Path,
    *,
    rows: int = 1 << 16,
    still_period: float | None = None,
    wiring_checks: bool = True,
) -> LogStream:
    """Pass 1 over a CSV or Parquet log named as ours (module docstring).

    Raises :class:`ChunkError` where the ordinary reader must take the log
    (and name the problem), :class:`LogError` for a log that cannot be used.
    """
    scan = LogScan(path, rows=rows, still_period=still_period, wiring_checks=wiring_checks)
    for chunk in read_chunks(scan.path, list(scan.names), rows=rows):
        scan.add(chunk)
    return scan.finish()


class LogScan:
    """What :func:`scan_log` keeps of a log, taken chunk by chunk (:meth:`add`): the time
    column, the median of ``az``, the channels' peaks and which have a finite sample, the
    first seconds (:attr:`head`) and the first :data:`~log_checks.WINDOW` s of motion
    (:attr:`wiring`). :meth:`finish` checks them and gives the :class:`LogStream`;
    :meth:`provisional` gives one of the samples taken so far (one read of a log,
    :func:`~wheelload.studies.pipeline.lean_estimate.estimate_lean`).

    Raises :class:`ChunkError` where the ordinary reader must take the log.
    """

    def __init__(
        self,
        path: Path,
        *,
        rows: int,
        still_period: float | None,
        wiring_checks: bool,
        time_column: bool = False,
    ) -> None:
        self.path = Path(path)
        self.source = source = str(self.path)
        present = chunk_columns(self.path)
        for name in REQUIRED:
            if name not in present:
                raise ChunkError(
                    f"{source}: missing column '{name}' "
                    "(a logger's names: give a channel map, --channels)"
                )
        for group in GROUPS:
            if 0 < sum(name in present for name in group) < len(group):
                raise ChunkError(f"{source}: a partial group of {group[0]}")
        ours = {"t", "ax", "ay", "az", "vx", *WHEEL_SPEED, *REFERENCE,
                *(n for g in GROUPS for n in g)}  # fmt: skip
        self.names = tuple(name for name in present if name in ours)
        self.rows, self.still_period, self.wiring_checks = rows, still_period, wiring_checks
        self.t_store, self.az_store = Appended(), Appended()
        self.peaks = {"d": np.zeros(4), "v": np.zeros(4), "vx": 0.0}
        self.travel_present = np.zeros(4, bool)
        self.reference_present = np.zeros(4, bool)
        self.stats = {"travel_count": np.zeros(4, np.int64), "travel_peak": np.zeros(4),
                      "rate_count": np.zeros(4, np.int64), "rate_min": np.full(4, np.inf),
                      "rate_max": np.full(4, -np.inf)}  # fmt: skip
        self.wiring, self.head = _Head(), _Head()
        self.wiring_end = None
        self.t0 = None
        self.speed_source = SpeedSource.LOGGED
        self.finite_counts = dict.fromkeys(("ax", "ay", "az", "vx"), 0)
        self.t = self.steps = None
        self.taken = 0
        if time_column:  # read first: the filter needs the whole log's steps from its start
            store = Appended()
            for chunk in read_chunks(self.path, ["t"], rows=PARQUET_ROWS):
                store.append(chunk["t"])
            self.t = store.array()
            if not self.t.size:
                raise ChunkError(f"{source}: no rows")
            self.steps = check_time_column(self.t, source)

    @property
    def settled(self) -> bool:
        """Whether the head and the wiring window are complete (what follows adds to neither)."""
        return self.head.done and (self.wiring.done or not self.wiring_checks)

    def add(self, chunk: dict[str, np.ndarray]) -> None:
        """Take the next chunk of the log's columns (:attr:`names`)."""
        n = len(chunk["t"])
        if n == 0:
            return
        t = chunk["t"]
        if self.t is None:
            self.t_store.append(t)
        else:  # the time column read before: the same stamps, or the file changed
            same = np.array_equal(self.t[self.taken : self.taken + n], t)
            release(self.t)
            if not same:
                raise LogError(f"{self.source}: changed while it was read: read it again")
        self.taken += n
        self.t0 = t[0] if self.t0 is None else self.t0
        peaks, stats = self.peaks, self.stats
        speed, self.speed_source = _speed(chunk, n)
        for name in self.finite_counts:
            if name in chunk:
                self.finite_counts[name] += int(np.count_nonzero(np.isfinite(chunk[name])))
        if "az" in chunk:
            self.az_store.append(chunk["az"])
        d = _travel(chunk, n)
        peaks["d"] = np.maximum(peaks["d"], _column_peak(d))
        finite = np.isfinite(d)
        self.travel_present |= finite.any(axis=0)
        stats["travel_count"] += finite.sum(axis=0)
        stats["travel_peak"] = np.maximum(
            stats["travel_peak"], np.max(np.abs(np.where(finite, d, 0.0)), axis=0)
        )
        if TRAVEL_RATE[0] in chunk:
            v = np.column_stack([chunk[name] for name in TRAVEL_RATE])
            peaks["v"] = np.maximum(peaks["v"], _column_peak(v))
            finite = np.isfinite(v)
            stats["rate_count"] += finite.sum(axis=0)
            stats["rate_min"] = np.minimum(
                stats["rate_min"], np.min(np.where(finite, v, np.inf), 0)
            )
            stats["rate_max"] = np.maximum(
                stats["rate_max"], np.max(np.where(finite, v, -np.inf), 0)
            )
        peaks["vx"] = max(peaks["vx"], float(np.nanmax(np.abs(speed), initial=0.0)))
        for i, name in enumerate(REFERENCE):
            if name in chunk:
                self.reference_present[i] |= bool(np.isfinite(chunk[name]).any())
        collected = dict(chunk, vx=speed)
        head, wiring = self.head, self.wiring
        if not head.done:
            stop = int(np.searchsorted(t, self.t0 + (self.still_period or 0.0), side="right"))
            head.add(collected, 0, min(stop + 1, n))  # one sample past the period
            head.done = stop < n
        if self.wiring_checks and not wiring.done:
            first = 0
            if self.wiring_end is None:
                moving = np.flatnonzero(np.abs(np.nan_to_num(speed)) > MOVING)
                if moving.size:
                    first = int(moving[0])
                    self.wiring_end = t[first] + WINDOW
            if self.wiring_end is not None:
                stop = int(np.searchsorted(t, self.wiring_end))
                wiring.add(collected, first, stop)
                wiring.done = stop < n

    def provisional(self) -> LogStream:
        """The :class:`LogStream` of the time column read first and the channels as far as
        taken: what the filter needs of the whole log (its channels' presence taken from
        the samples read so far, :meth:`LogStream.filter_facts`)."""
        return self._stream(self.t, self.steps)

    def finish(self) -> LogStream:
        """The whole log's :class:`LogStream`, its time column and units checked
        (:class:`LogError` for a log that cannot be used)."""
        if self.t is not None:
            if self.taken != self.t.size:
                raise LogError(f"{self.source}: changed while it was read: read it again")
            t, steps = self.t, self.steps
        else:
            t = self.t_store.array()
            if not t.size:
                raise ChunkError(f"{self.source}: no rows")
            steps = check_time_column(t, self.source)
        sparse = [name for name, count in self.finite_counts.items() if name in self.names
                  and (count == 0 or (name == "vx" and count <= 0.5 * t.size))]  # fmt: skip
        if sparse:  # the ordinary reader names an empty channel, assumes az, interpolates vx
            raise ChunkError(f"{self.source}: column '{sparse[0]}' is empty or slower than the log")
        say_gaps(steps, self.source)
        az_median = _nanmedian(self.az_store.array())
        peaks = self.peaks
        check_units(
            np.array([[0.0, 0.0, az_median]]),
            peaks["d"][None, :],
            peaks["v"][None, :] if TRAVEL_RATE[0] in self.names else None,
            np.array([peaks["vx"]]),
            self.source,
        )
        stream = self._stream(t, steps)
        if stream.velocities_derived:
            Differentiator(steps, 4, VELOCITY_CUTOFF, self.source)  # its checks, before output
        return stream

    def _stream(self, t: np.ndarray, steps: Steps) -> LogStream:
        names, source = self.names, self.source
        az_assumed = "az" not in names
        return LogStream(
            path=self.path,
            source=source,
            names=names,
            t=t,
            steps=steps,
            travel_present=self.travel_present.copy(),
            reference_present=(
                self.reference_present.copy() if any(n in names for n in REFERENCE) else None
            ),
            velocities_derived=TRAVEL_RATE[0] not in names and bool(self.travel_present.any()),
            az_assumed=az_assumed,
            speed_source=self.speed_source,
            channel_stats=ChannelStats(**{k: np.copy(v) for k, v in self.stats.items()}),
            wiring=_signals(self.wiring, source, az_assumed) if self.wiring.parts else None,
            head=_signals(self.head, source, az_assumed),
            rows=self.rows,
        )


def _nanmedian(values: np.ndarray) -> float:
    """``np.nanmedian`` of a column that may be on disk, a block at a time (NaN if all are;
    the median of the rest by :func:`~order_statistics.blocked_median`)."""
    block = 1 << 16

    def blocks():
        for start in range(0, values.size, block):
            part = values[start : start + block]
            yield part[~np.isnan(part)]
            release(values)

    count = sum(part.size for part in blocks())
    return float(order_statistics.blocked_median(blocks, count)) if count else np.nan


def _signals(head: _Head, source: str, az_assumed: bool) -> Signals:
    """A :class:`Signals` of the collected samples (what the checks read of it)."""
    t = head.array("t")
    n = t.size
    az = np.full(n, GRAVITY) if az_assumed else head.array("az")
    d = np.column_stack([head.array(name) for name in TRAVEL]) if TRAVEL[0] in head.parts else None
    rates = np.column_stack([head.array(n) for n in RATES]) if RATES[0] in head.parts else None
    if n < 2:  # a one-sample window: the checks find too little motion
        t, az = np.array([t[0], t[0] + 1e-9]), np.resize(az, 2)
        n = 2
        d = None if d is None else np.resize(d, (2, 4))
        rates = None if rates is None else np.resize(rates, (2, 3))
        vx, ax, ay = (np.resize(head.array(k), 2) for k in ("vx", "ax", "ay"))
    else:
        vx, ax, ay = (head.array(k) for k in ("vx", "ax", "ay"))
    return Signals(
        t=t,
        vx=vx,
        acc=np.column_stack([ax, ay, az]),
        d=np.full((n, 4), np.nan) if d is None else d,
        v=np.full((n, 4), np.nan),
        rates=rates,
        source=source,
    )
