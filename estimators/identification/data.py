"""Identification data: component-rig CSV files and drive logs with reference loads.

Corner rig file (spring + damper unit of one corner): columns ``d`` [m,
compression from static], ``v`` [m/s, > 0 in compression], ``force`` [N,
change of the wheel load from static, > 0 pushes the wheel down]; optional
``t`` [s]. The corner (``fl``, ``fr``, ``rl``, ``rr``) is a column
``corner`` (one file may hold several) or a header line ``# corner = fl``.

Anti-roll-bar rig file: columns ``d_left``, ``d_right`` [m], ``force`` [N,
load the bar adds to the left wheel; the right wheel gets the opposite];
optional ``t``. The axle (``front``, ``rear``) is a column ``axle`` or a
header line ``# axle = front``.

Drive log: the log format of :mod:`wheelload.estimators.logs.signals`, with
reference loads ``fz_fl .. fz_rr`` for any subset of the wheels (a missing
column or a blank cell: no reference there).

Example
-------
>>> sets = read_rig("rig_corner.csv") + (read_drive("drive.csv"),)
"""

from __future__ import annotations

import enum
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.logs.signals import rate_derivatives, signals_from_frame
from wheelload.estimators.types import RATE_DERIVATIVES, RATES, TRAVEL, TRAVEL_RATE, LogError
from wheelload.models.conventions import AXLES, WHEELS
from wheelload.models.runtime import spill
from wheelload.models.runtime.spill import SPILL_BYTES, release

CORNER_COLUMNS = ("d", "v", "force")
ARB_COLUMNS = ("d_left", "d_right", "force")
BLOCK = 1 << 16  # samples per block of a pass over a data set that may be on disk
HEADER_KEY = re.compile(r"^#\s*(\w+)\s*=\s*(\S+)\s*$")


class DataKind(enum.Enum):
    CORNER_RIG = "corner rig"
    ARB_RIG = "anti-roll-bar rig"
    DRIVE = "drive log"


@dataclass(frozen=True, kw_only=True, eq=False)
class DataSet:
    """One block of identification data.

    ``signals`` maps a model signal input (drive logs) or a rig column to
    its samples, shape (n, size); ``target`` holds the measured force per
    model row (n, rows), NaN where there is none; ``rows`` names the model
    rows (wheel names), ``location`` is the corner index (corner rig) or
    axle index (bar rig), unused for drive logs.
    """

    kind: DataKind
    source: str
    t: np.ndarray
    signals: dict[str, np.ndarray]
    target: np.ndarray
    rows: tuple[str, ...]
    location: int = -1
    absent: frozenset[str] = frozenset()  # optional channels the log lacks (filled with 0)

    def __len__(self) -> int:
        return len(self.t)

    def release(self) -> None:
        """Drop the pages of a data set kept on disk from memory (:func:`.spill.release`)."""
        release(self.t, self.target, *self.signals.values())

    def blocks(self, size: int) -> Iterator[tuple[int, int]]:
        """Sample ranges ``(start, stop)`` of at most ``size``, the data set's pages dropped
        after each (a pass over a long log holds one block)."""
        for start in range(0, len(self), size):
            yield start, min(start + size, len(self))
            self.release()

    def label(self) -> str:
        if self.kind is DataKind.CORNER_RIG:
            suffix = f" ({WHEELS[self.location]})"
        elif self.kind is DataKind.ARB_RIG:
            suffix = f" ({AXLES[self.location]})"
        else:
            suffix = ""
        return f"{Path(self.source).name}{suffix}"

    def subset(self, index: np.ndarray) -> DataSet:
        """The samples at ``index`` (e.g. a shorter record for a convergence test)."""
        return DataSet(
            kind=self.kind,
            source=self.source,
            t=self.t[index],
            signals={k: v[index] for k, v in self.signals.items()},
            target=self.target[index],
            rows=self.rows,
            location=self.location,
            absent=self.absent,
        )

    def with_target(self, target: np.ndarray) -> DataSet:
        """The same samples with another target (e.g. outliers injected)."""
        return DataSet(
            kind=self.kind,
            source=self.source,
            t=self.t,
            signals=self.signals,
            target=np.asarray(target, float).reshape(self.target.shape),
            rows=self.rows,
            location=self.location,
            absent=self.absent,
        )


def _header_keys(path: Path) -> dict[str, str]:
    keys = {}
    with path.open(encoding="utf-8") as stream:
        for line in stream:
            if not line.startswith("#"):
                break
            match = HEADER_KEY.match(line.strip())
            if match:
                keys[match.group(1).lower()] = match.group(2).strip().lower()
    return keys


def _numeric(frame: pd.DataFrame, name: str, source: str) -> np.ndarray:
    values = pd.to_numeric(frame[name], errors="coerce").to_numpy(float)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise LogError(
            f"{source}: column '{name}' is not a finite number at row {bad[0]}: "
            f"{frame[name].iloc[bad[0]]!r} (remove or fix the row)"
        )
    return values


def _groups(frame: pd.DataFrame, path: Path, key: str, choices: tuple[str, ...]):
    """Row indices per location, from a column ``key`` or the header key ``# key = ...``."""
    source = str(path)
    if key in frame.columns:
        labels = frame[key].astype(str).str.strip().str.lower().to_numpy()
        unknown = sorted(set(labels) - set(choices))
        if unknown:
            row = int(np.flatnonzero(labels == unknown[0])[0])
            raise LogError(
                f"{source}: column '{key}' has '{unknown[0]}' at row {row}: "
                f"use one of {', '.join(choices)}"
            )
        return [(choices.index(c), np.flatnonzero(labels == c)) for c in choices if c in labels]
    header = _header_keys(path)
    if key not in header:
        raise LogError(
            f"{source}: which {key} is it? add a column '{key}' or a first line "
            f"'# {key} = {choices[0]}' ({', '.join(choices)})"
        )
    if header[key] not in choices:
        raise LogError(
            f"{source}: header key '{key} = {header[key]}': use one of {', '.join(choices)}"
        )
    return [(choices.index(header[key]), np.arange(len(frame)))]


def _time(frame: pd.DataFrame, source: str) -> np.ndarray:
    if "t" in frame.columns:
        return _numeric(frame, "t", source)
    return np.arange(len(frame), dtype=float)


def read_rig(path: str | Path) -> tuple[DataSet, ...]:
    """Read a corner or anti-roll-bar rig CSV (see module docstring) into data sets."""
    path = Path(path)
    source = str(path)
    if not path.exists():
        raise LogError(f"{source}: no such rig file")
    try:
        frame = pd.read_csv(path, comment="#")
    except LogError:
        raise
    except (pd.errors.ParserError, pd.errors.EmptyDataError, OSError, ValueError) as error:
        raise LogError(f"{source}: cannot be read: {error}") from None
    frame = frame.rename(columns=lambda name: str(name).strip())
    if set(ARB_COLUMNS) <= set(frame.columns):
        kind, columns, key, choices = DataKind.ARB_RIG, ARB_COLUMNS, "axle", AXLES
    elif set(CORNER_COLUMNS) <= set(frame.columns):
        kind, columns, key, choices = DataKind.CORNER_RIG, CORNER_COLUMNS, "corner", WHEELS
    else:
        raise LogError(
            f"{source}: a rig file needs columns {', '.join(CORNER_COLUMNS)} (corner) or "
            f"{', '.join(ARB_COLUMNS)} (anti-roll bar); has {', '.join(map(str, frame.columns))}"
        )
    if len(frame) < 2:
        raise LogError(f"{source}: needs at least 2 rows, has {len(frame)}")
    values = {name: _numeric(frame, name, source) for name in columns}
    t = _time(frame, source)
    sets = []
    for location, index in _groups(frame, path, key, choices):
        row = WHEELS[location] if kind is DataKind.CORNER_RIG else WHEELS[2 * location]
        sets.append(
            DataSet(
                kind=kind,
                source=source,
                t=t[index],
                signals={name: values[name][index, None] for name in columns[:2]},
                target=values["force"][index, None],
                rows=(row,),
                location=location,
            )
        )
    return tuple(sets)


def drive_gates(p, sets: tuple[DataSet, ...]) -> tuple[float, ...]:
    """Term gates of the vehicle's [model] switches for the drive logs in ``sets``.

    A term whose optional input one of the logs lacks is off for all of them
    (the model's gates are constants of the fit).
    """
    from wheelload.estimators.identification.model import model_gates

    absent = frozenset().union(*(s.absent for s in sets if s.kind is DataKind.DRIVE))
    return model_gates(p, absent)


def read_drive(
    path: str | Path,
    channels: tuple[str, ...],
    optional: frozenset[str] = frozenset(),
    *,
    channel_map: str | Path | None = None,
    wiring_checks: bool = True,
    in_memory: bool = False,
    spill_bytes: int = SPILL_BYTES,
) -> DataSet:
    """Read a drive log with reference loads for the model's signal ``channels``.

    A channel is taken from the validated log (travel rates derived when not
    logged) or, failing that, from a column of that name; an ``optional``
    channel the log lacks is 0. With a ``channel_map`` the log (any format
    :func:`~wheelload.estimators.logs.signals.read_log` reads) is read through it,
    with its wiring checks unless ``wiring_checks`` is off.

    A CSV or Parquet log named as ours is read chunk by chunk, its data set kept
    on disk when larger than ``spill_bytes`` (:mod:`.spill`; memory: one chunk
    and the time stamps while reading); any other, or with ``in_memory``, as a
    whole table in memory (the same data set, to the bit).
    """
    path = Path(path)
    source = str(path)
    if not path.exists():
        raise LogError(f"{source}: no such log file")
    suffix = path.suffix.lower()
    if channel_map is None and not in_memory:
        data = _read_drive_chunks(path, channels, optional, wiring_checks, spill_bytes)
        if data is not None:
            return data
    try:
        if channel_map is not None:
            from wheelload.estimators.logs.signals import read_log

            frame = read_log(path, channels=channel_map, wiring_checks=wiring_checks).to_frame()
        elif suffix == ".csv":
            frame = pd.read_csv(path, comment="#")
        else:
            frame = pd.read_parquet(path)
    except LogError:
        raise
    except (pd.errors.ParserError, pd.errors.EmptyDataError, OSError, ValueError) as error:
        raise LogError(f"{source}: cannot be read: {error}") from None
    frame = frame.rename(columns=lambda name: str(name).strip())
    _check_reference(frame.columns, source)
    reference = np.full((len(frame), 4), np.nan)
    for i, wheel in enumerate(WHEELS):
        name = f"fz_{wheel}"
        if name in frame.columns:
            reference[:, i] = pd.to_numeric(frame[name], errors="coerce").to_numpy(float)
    _check_reference(frame.columns, source, np.isfinite(reference).any())
    signals = signals_from_frame(
        frame.drop(columns=[c for c in frame.columns if c.startswith("fz_")]),
        source=source,
        wiring_checks=wiring_checks,
    )
    _check_travel(channels, source, np.isfinite(signals.d).any())
    validated = signals.to_frame()
    if signals.az_assumed:  # g, as the estimators take it
        validated["az"] = signals.acc[:, 2]
    if signals.rates is not None and signals.rate_dots is None:
        derived = rate_derivatives(signals)
        if np.isfinite(derived).any():
            validated[list(RATE_DERIVATIVES)] = derived
    table = {}
    absent = set()
    for name in channels:
        if name in validated.columns:
            values = validated[name].to_numpy(float)
        elif name in frame.columns:
            values = pd.to_numeric(frame[name], errors="coerce").to_numpy(float)
        elif name in optional:
            values = np.zeros(len(frame))
            absent.add(name)
        else:
            raise _no_channel(source, name)
        table[name] = values[:, None]
    return _drive_set(source, signals.t, table, reference, absent)


def _drive_set(source: str, t, table: dict, reference: np.ndarray, absent: set) -> DataSet:
    """The drive log's data set; no reference where a channel has no finite sample."""
    for start in range(0, len(t), BLOCK):
        block = slice(start, start + BLOCK)
        for values in table.values():
            reference[block][~np.isfinite(values[block, 0])] = np.nan
        release(reference, *table.values())
    return DataSet(
        kind=DataKind.DRIVE,
        source=source,
        t=t,
        signals=table,
        target=reference,
        rows=WHEELS,
        absent=frozenset(absent),
    )


def _check_reference(columns, source: str, finite: bool = True) -> None:
    """A drive log needs a reference load: some ``fz_*`` column with a finite sample."""
    if not finite or not any(f"fz_{w}" in columns for w in WHEELS):
        raise LogError(
            f"{source}: no reference loads: give at least one of "
            + ", ".join(f"fz_{w}" for w in WHEELS)
        )


def _no_channel(source: str, name: str) -> LogError:
    return LogError(f"{source}: the suspension model needs channel '{name}', not in the log")


def _check_travel(channels: tuple[str, ...], source: str, present: bool) -> None:
    travels = [name for name in channels if name.startswith("d_")]
    if travels and not present:
        raise LogError(
            f"{source}: no suspension travel ({', '.join(travels)}): the maps are fitted to "
            "the travels against the reference loads; log the travel sensors (or map them "
            "with --channels)"
        )


def _read_drive_chunks(
    path: Path,
    channels: tuple[str, ...],
    optional: frozenset[str],
    wiring_checks: bool,
    spill_bytes: int,
) -> DataSet | None:
    """:func:`read_drive` of a CSV or Parquet log named as ours, read chunk by chunk
    (:meth:`~wheelload.estimators.kf.log_stream.LogStream.signal_chunks`: the same
    checks and derived signals as the whole-log reader, to the bit), so that memory is the
    data set's columns (on disk when larger than ``spill_bytes``) and one chunk, not the
    log's table several times over. None for a log the chunked reader cannot take as plain
    numbers (read it the ordinary way)."""
    from wheelload.estimators.kf.log_stream import scan_log
    from wheelload.estimators.logs.checks import raise_for_wiring
    from wheelload.estimators.logs.readers.chunks import ChunkError, chunk_columns

    source = str(path)
    try:
        present = chunk_columns(path)
        _check_reference(present, source)
        stream = scan_log(path, wiring_checks=wiring_checks)
    except ChunkError:
        return None
    if stream.reference_present is None or not stream.reference_present.any():
        _check_reference((), source)
    _check_travel(channels, source, bool(stream.travel_present.any()))
    if wiring_checks:
        raise_for_wiring(stream.wiring_report(), source)
    n = len(stream)
    derived_rate_dots = RATES[0] in stream.names and RATE_DERIVATIVES[0] not in stream.names
    filled: list[str] = []
    absent: set[str] = set()
    for name in channels:
        if name in present or name in ("vx", "az", *TRAVEL, *TRAVEL_RATE):
            filled.append(name)  # read, derived, or missing (NaN) as in Signals
        elif name in RATE_DERIVATIVES and derived_rate_dots:
            filled.append(name)
        elif name in optional:
            absent.add(name)
        else:
            raise _no_channel(source, name)
    arrays = spill.columns(
        {"t": 1, "target": len(WHEELS)} | dict.fromkeys(filled, 1), n, spill_bytes
    )
    t, reference = arrays.pop("t")[:, 0], arrays.pop("target")
    table = arrays
    extra = tuple(name for name in table if name in present)
    start = 0
    try:
        for chunk_t, chunk in stream.signal_chunks(extra):
            stop = start + chunk_t.size
            t[start:stop] = chunk_t
            for i, wheel in enumerate(WHEELS):
                reference[start:stop, i] = chunk.get(f"fz_{wheel}", np.nan)
            for name, values in table.items():
                values[start:stop, 0] = chunk.get(name, np.nan)
            release(t, reference, *table.values())
            start = stop
    except ChunkError:
        return None
    del stream  # its time stamps: the data set has them
    for name in RATE_DERIVATIVES:  # none derived (too irregular, no rate): as if not logged
        if name in table and name not in present and not _any_finite(table[name]):
            if name not in optional:
                raise _no_channel(source, name)
            del table[name]
            absent.add(name)
    for name in absent:
        table[name] = np.broadcast_to(np.zeros((1, 1)), (n, 1))  # read-only, no memory
    table = {name: table[name] for name in channels}
    return _drive_set(source, t, table, reference, absent)


def _any_finite(values: np.ndarray) -> bool:
    """Whether a column (perhaps on disk) has a finite sample, a block at a time."""
    for start in range(0, len(values), BLOCK):
        if np.isfinite(values[start : start + BLOCK]).any():
            return True
        release(values)
    return False
