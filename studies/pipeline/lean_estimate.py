"""One CSV or Parquet log through the lean whole-log path: memory bounded by the chunk.

The log is read once. Its first chunks are held until the first seconds (still
period) and the first :data:`~wheelload.estimators.logs.checks.WINDOW` s of motion
(wiring checks) are in (:class:`~wheelload.estimators.LogScan`); the checks and the
static loads run on them, and the filter starts on the chunks held and goes on with
each chunk as it is read, through the compiled column loop: each chunk is scanned
(time column, channels' peaks), estimated, written (``out``) and summarised
(:class:`~wheelload.studies.pipeline.estimate_digest.EstimateDigest`) before the next
is read. What the filter takes of the whole log (the median sample interval, the time
stamps' uniformity, which channels have a sample) is taken from the chunks held and
checked against the whole log at its end, before ``out`` is renamed into place: a log
whose later samples differ in these is estimated again from a second read (as is one
whose first seconds of motion do not fit in :data:`HELD_BYTES`, read once to scan it,
then again to estimate it; and one whose file check finds a model error). The
estimates are those of :meth:`TwoStageKF.run` on the whole log, to the bit.
``wheelload estimate`` takes this path for one log and, for long logs, for each log of
many (:mod:`wheelload.studies.pipeline.batch`).
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators.registry import build, method
from wheelload.estimators.result import SensorFault
from wheelload.models import Vehicle, load_vehicle
from wheelload.studies.pipeline.estimate_digest import EstimateDigest
from wheelload.studies.pipeline.log_preparation import prepare_log
from wheelload.studies.pipeline.measured_static import (
    corner_weights,
    still_period,
    without_travel,
)
from wheelload.studies.pipeline.run_messages import log_stream, phase

logger = logging.getLogger(__name__)

if TYPE_CHECKING:
    from wheelload.estimators import LogStream


@dataclass(frozen=True, kw_only=True)
class LeanResult:
    """A log estimated on the lean path: its scan, the digest of its estimates, the lines
    to tell the user."""

    stream: LogStream
    vehicle: Vehicle
    digest: EstimateDigest
    faults: tuple[SensorFault, ...]
    notes: tuple[str, ...]
    warnings: tuple[str, ...]


def takes_lean_path(path: Path, settings) -> bool:
    """Whether the lean path can take this log (a method with the compiled whole-log paths,
    :attr:`MethodInfo.compiled_batch`, not smoothed, on a CSV/Parquet log named as ours);
    ``settings`` an :class:`~wheelload.studies.pipeline.batch.EstimateSettings`."""
    return (
        method(settings.method).compiled_batch
        and not settings.smooth
        and settings.channels is None
        and path.suffix.lower() in (".csv", ".parquet", ".pq")
    )


#: Bytes of a log's first chunks held while the first seconds of motion are read (the
#: wiring window); a log still standing beyond them is scanned first, then estimated.
HELD_BYTES = 64 << 20


class _Differs(Exception):
    """The whole log differs from its first chunks in what the filter takes of it."""


def estimate_lean(
    path: Path, settings, out: Path | None, *, force: bool = False
) -> LeanResult | None:
    """Estimate ``path`` chunk by chunk, writing ``out`` (CSV or Parquet) if given.

    None (nothing written) for a log the chunked reader cannot take as plain
    numbers: the ordinary reader then reads it and names the problem.
    """
    from wheelload.estimators import LogScan
    from wheelload.estimators.logs.readers.chunks import ChunkError, read_chunks

    try:
        with phase("read (time column)"):
            scan = LogScan(
                path,
                rows=1 << 16,
                still_period=settings.still_period,
                wiring_checks=settings.wiring_checks,
                time_column=True,
            )
        reader = read_chunks(scan.path, list(scan.names), rows=scan.rows)
        with phase("read (first chunks)"):
            held, complete = _first_chunks(scan, reader)
        first = _provisional(scan, held, complete)
        if first is None:  # standing beyond the chunks held, or a time column to refuse
            with phase("read (scan)"):
                for chunk in reader:
                    scan.add(chunk)
                stream = scan.finish()
            log_stream(stream)
            return _estimate(path, settings, out, force, stream)
        return _estimate(path, settings, out, force, first, scan=scan, chunks=(held, reader))
    except ChunkError:
        return None


def _first_chunks(scan, reader) -> tuple[list[dict], bool]:
    """Chunks read (and scanned) until the scan is settled, or beyond :data:`HELD_BYTES`;
    whether they are the whole log."""
    held, size = [], 0
    for chunk in reader:
        scan.add(chunk)
        held.append(chunk)
        size += sum(values.nbytes for values in chunk.values())
        if scan.settled or size > HELD_BYTES:
            return held, False
    return held, True


def _provisional(scan, held: list[dict], complete: bool) -> LogStream | None:
    """The stream of the chunks held, or None where the filter cannot start on them (the
    log standing beyond them)."""
    if not (scan.settled or complete) or not held:
        return None
    return scan.provisional()


def _estimate(path, settings, out, force, stream, *, scan=None, chunks=None) -> LeanResult:
    """The checks, the filter over the log's chunks and the file check; ``scan`` and
    ``chunks`` (the chunks held, then the reader): the log read once, ``stream`` the
    stream of the chunks held (module docstring)."""
    from wheelload.estimators import ThinnedInputs
    from wheelload.estimators.logs.model_error import MAX_SAMPLES
    from wheelload.studies.pipeline.log_warnings import channel_warnings, negative_load_warnings

    prepared = prepare_log(
        load_vehicle(settings.vehicle, allow_unusual=settings.allow_unusual),
        settings,
        source=stream.source,
        wiring_report=stream.wiring_report,
        checked_signals=lambda: stream.wiring or stream.head,
        static_loads=lambda vehicle: static_loads_for(stream, vehicle, settings),
    )
    vehicle, static, notes = prepared.vehicle, prepared.static, prepared.notes
    kf = build(settings.method, vehicle, static=static)
    thinned = None
    if scan is not None:
        first, whole = stream, None

        def verify():
            nonlocal whole
            whole = scan.finish()
            if first.filter_facts() != whole.filter_facts():
                raise _Differs

        thinned = ThinnedInputs(MAX_SAMPLES)
        try:
            digest, faults = _estimate_chunks(
                stream, kf, out, force, source=_scanned(scan, *chunks), thinned=thinned,
                verify=verify,
            )  # fmt: skip
            stream = whole
        except _Differs:
            logger.info("the log's later samples differ from its first: estimated again")
            stream, thinned = whole, None
            digest, faults = _estimate_chunks(stream, kf, out, force)
        log_stream(stream)
    else:
        digest, faults = _estimate_chunks(stream, kf, out, force)
    # The file check (estimators/logs/model_error.py) on every k-th sample; a finding that
    # changes the estimates (a travel zero taken off, σ widened) runs the log again.
    properties = None if digest.mass_properties is None else digest.mass_properties[:4]
    diagnosis = stream.file_check(
        vehicle, faults, properties, static_given=static is not None, thinned=thinned
    )
    if diagnosis.finding is not None:
        digest, faults = _estimate_chunks(stream, kf, out, True, diagnosis)
        digest.model_errors = (diagnosis.finding,)
    stats = stream.channel_stats
    warnings = channel_warnings(
        stream.source,
        stream.sample_rate,
        travel_count=stats.travel_count,
        travel_peak=stats.travel_peak,
        rate_count=stats.rate_count,
        rate_min=stats.rate_min,
        rate_max=stats.rate_max,
        velocities_derived=stream.velocities_derived,
    ) + negative_load_warnings(digest.negative_samples, digest.load_min, str(path))
    return LeanResult(
        stream=stream,
        vehicle=vehicle,
        digest=digest,
        faults=tuple(faults),
        notes=tuple(notes),
        warnings=tuple(warnings),
    )


def _scanned(scan, held: list[dict], reader) -> Iterator[dict]:
    """The chunks held (let go as they are handed on), then the rest of the log, scanned."""
    while held:
        yield held.pop(0)
    for chunk in reader:
        scan.add(chunk)
        yield chunk


def _estimate_chunks(
    stream: LogStream,
    kf,
    out: Path | None,
    force: bool,
    diagnosis=None,
    *,
    source=None,
    thinned=None,
    verify=None,
):
    """The log's estimates chunk by chunk into a digest (and ``out``); the faults found.
    ``source``, ``thinned``: as :meth:`LogStream.chunks`; ``verify()`` is called once the
    last chunk is estimated, before ``out`` is renamed into place (an error leaves no
    ``out``)."""
    from wheelload.estimators.logs.output_files import table_writer

    samples = len(stream) if source is None else None
    digest = EstimateDigest(samples=samples, reference_wheels=stream.reference_present)
    faults: list[SensorFault] = []
    start, writing = time.perf_counter(), 0.0
    with contextlib.ExitStack() as stack:
        write = (
            stack.enter_context(table_writer(Path(out), replace=force)) if out is not None else None
        )
        chunks = stream.chunks(
            kf, faults=faults, diagnosis=diagnosis, source=source, thinned=thinned
        )
        for chunk in chunks:
            if write is not None:
                handed = time.perf_counter()
                write(chunk.columns())
                writing += time.perf_counter() - handed
            digest.add(chunk.loads, chunk.std, chunk.flags, chunk.reference)
            digest.add_mass_properties(chunk.mass_properties)
        if verify is not None:
            verify()
        closing = time.perf_counter()
    writing += time.perf_counter() - closing
    total = time.perf_counter() - start
    again = ", run again after the file check" if diagnosis is not None else ""
    read = "" if source is None else ", scanned"
    logger.info("filter (chunks read%s, estimated, digested%s): %.3f s", read, again,
                total - writing)  # fmt: skip
    if out is not None:
        logger.info("write %s (handing chunks to the writer, closing it): %.3f s", out, writing)
    return digest, faults


def static_loads_for(stream: LogStream, vehicle: Vehicle, settings):
    """Static loads from corner weights and a still period, as ``estimate_log`` sets them.

    The still-period check reads the first samples only (``stream.head``); a travel
    channel of the log with no sample in the period is refused as on the whole log.
    """
    static, notes = corner_weights(settings)
    if static is not None and not stream.travel_present.any():
        notes = [without_travel(static, vehicle)]
    head = stream.head
    if settings.still_period:
        window = head.t <= head.t[0] + settings.still_period
        if settings.still_period > 0 and np.any(
            stream.travel_present & ~np.isfinite(head.d[window]).any(axis=0)
        ):
            raise ValueError(f"{stream.source}: a travel channel has no sample in the still period")
    static, still = still_period(head, vehicle, settings, static)
    return static, notes + still
