"""One CSV or Parquet log through the lean whole-log path: memory bounded by the chunk.

The log is scanned (:func:`~wheelload.estimators.scan_log`: time
column, wiring window, sensor set), then read again chunk by chunk through
the compiled column loop; each chunk is written (``out``) and summarised
(:class:`~wheelload.studies.pipeline.estimate_digest.EstimateDigest`) before the next
is read. The estimates are those of :meth:`TwoStageKF.run` on the whole log,
to the bit. ``wheelload estimate`` takes this path for one log and, for long
logs, for each log of many (:mod:`wheelload.studies.pipeline.batch`).
"""

from __future__ import annotations

import contextlib
import logging
import time
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


def estimate_lean(
    path: Path, settings, out: Path | None, *, force: bool = False
) -> LeanResult | None:
    """Estimate ``path`` chunk by chunk, writing ``out`` (CSV or Parquet) if given.

    None (nothing written) for a log the chunked reader cannot take as plain
    numbers: the ordinary reader then reads it and names the problem.
    """
    from wheelload.estimators import scan_log
    from wheelload.estimators.logs.readers.chunks import ChunkError
    from wheelload.studies.pipeline.log_warnings import channel_warnings, negative_load_warnings

    try:
        with phase("read (scan)"):
            stream = scan_log(
                path, still_period=settings.still_period, wiring_checks=settings.wiring_checks
            )
    except ChunkError:
        return None
    log_stream(stream)
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
    digest, faults = _estimate_chunks(stream, kf, out, force)
    # The file check (estimators/logs/model_error.py) on every k-th sample; a finding that
    # changes the estimates (a travel zero taken off, σ widened) runs the log again.
    properties = None if digest.mass_properties is None else digest.mass_properties[:4]
    diagnosis = stream.file_check(vehicle, faults, properties, static_given=static is not None)
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


def _estimate_chunks(stream: LogStream, kf, out: Path | None, force: bool, diagnosis=None):
    """The log's estimates chunk by chunk into a digest (and ``out``); the faults found."""
    from wheelload.estimators.logs.output_files import table_writer

    digest = EstimateDigest(samples=len(stream), reference_wheels=stream.reference_present)
    faults: list[SensorFault] = []
    start, writing = time.perf_counter(), 0.0
    with contextlib.ExitStack() as stack:
        write = (
            stack.enter_context(table_writer(Path(out), replace=force)) if out is not None else None
        )
        for chunk in stream.chunks(kf, faults=faults, diagnosis=diagnosis):
            if write is not None:
                handed = time.perf_counter()
                write(chunk.columns())
                writing += time.perf_counter() - handed
            digest.add(chunk.loads, chunk.std, chunk.flags, chunk.reference)
            digest.add_mass_properties(chunk.mass_properties)
        closing = time.perf_counter()
    writing += time.perf_counter() - closing
    total = time.perf_counter() - start
    again = ", run again after the file check" if diagnosis is not None else ""
    logger.info("filter (chunks read, estimated, digested%s): %.3f s", again, total - writing)
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
