"""Many logs: estimate each, write one output per log and one summary table.

Logs are given as files, folders (every log file inside, not recursive) or
glob patterns. :func:`run_logs` processes them serially, on local worker
processes, or on an existing Dask cluster, with a progress bar; the summary
rows are sorted by log path, so every way gives the same table.

Example
-------
>>> table = run_logs(expand_logs(["fleet/"]), settings, workers=2)
"""

from __future__ import annotations

import functools
import threading
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators import (
    Estimate,
    Signals,
    guard_settings_for,
    read_log,
)
from wheelload.estimators.codegen.batched import run_batched
from wheelload.estimators.logs.checks import check_wiring
from wheelload.estimators.logs.output_files import write_frame
from wheelload.estimators.logs.signals import coarse_travel_note
from wheelload.estimators.protocol import Estimator
from wheelload.estimators.registry import build, method, methods
from wheelload.models import Vehicle, load_vehicle
from wheelload.studies.pipeline.log_preparation import prepare_log
from wheelload.studies.pipeline.log_settings import (  # noqa: F401  (named from here too)
    EstimateSettings,
    expand_logs,
)
from wheelload.studies.pipeline.log_warnings import load_warnings, signal_warnings
from wheelload.studies.pipeline.measured_static import measured_static_loads, with_travel_zeroed
from wheelload.studies.pipeline.run_messages import log_signals, phase
from wheelload.studies.pipeline.summary import LoadFigures, LogHeader, summary_row
from wheelload.studies.workers import ignore_interrupts

if TYPE_CHECKING:
    import pandas as pd

SUMMARY_NAME = "summary.csv"


@dataclass(frozen=True, kw_only=True)
class LogResult:
    """One log's signals, estimate and the lines to tell the user."""

    signals: Signals
    estimate: Estimate
    vehicle: Vehicle
    notes: tuple[str, ...]
    warnings: tuple[str, ...]


_lock = threading.Lock()


@functools.lru_cache(maxsize=4)
def _vehicle(path: Path, allow_unusual: bool = False) -> Vehicle:
    return load_vehicle(path, allow_unusual=allow_unusual)


@functools.lru_cache(maxsize=8)
def _filter(
    vehicle: Path,
    allow_unusual: bool,
    static: tuple[float, ...] | None,
    zeroed: bool,
    name: str = "kf",
) -> Estimator:
    """The method ``name`` (one with :attr:`MethodInfo.compiled_batch`, the two-stage KF by
    default) whose compiled loop is built, cached per process; ``zeroed``: the travel is
    zeroed at the log's start (:func:`payload_reference`)."""
    initial = None if static is None else np.array(static)
    description = _vehicle(vehicle, allow_unusual)
    description = with_travel_zeroed(description) if zeroed else description
    kf = build(name, description, static=initial)
    kf.run(Signals(t=np.array([0.0, 0.01]), vx=np.zeros(2), acc=np.zeros((2, 3)),
                   d=np.zeros((2, 4)), v=np.zeros((2, 4))))  # fmt: skip
    return kf


def compiled_methods() -> tuple[str, ...]:
    """The methods whose registry entry offers the compiled whole-log paths (static loads
    measured from the log, smoothing, the lean path): :attr:`MethodInfo.compiled_batch`."""
    return tuple(name for name, info in methods().items() if info.compiled_batch)


def _prepare_log(path: Path, settings: EstimateSettings):
    """Read one log, run the wiring checks, set the static loads: ``(vehicle, signals, notes,
    static)``."""
    vehicle = _vehicle(settings.vehicle, settings.allow_unusual)
    with phase("read"):
        signals = read_log(path, channels=settings.channels, wiring_checks=False)
    log_signals(signals, settings.channels)
    coarse = coarse_travel_note(signals.travel_quantum, guard_settings_for(vehicle).stuck_motion)
    prepared = prepare_log(
        vehicle,
        settings,
        source=signals.source,
        wiring_report=lambda: check_wiring(
            signals.t,
            signals.vx,
            signals.acc,
            signals.d,
            signals.rates,
            own_clocks=signals.own_clocks,
        ),  # fmt: skip
        checked_signals=lambda: signals,
        static_loads=lambda vehicle: measured_static_loads(signals, vehicle, settings),
        notes=() if coarse is None else (coarse,),
    )
    return prepared.vehicle, signals, list(prepared.notes), prepared.static


def estimate_log(path: Path, settings: EstimateSettings) -> LogResult:
    """Read one log, set the static loads, run the chosen estimator (default: the two-stage KF)."""
    vehicle, signals, notes, static = _prepare_log(path, settings)
    if method(settings.method).compiled_batch:
        key = None if static is None else tuple(float(f) for f in static)
        with _lock:  # build (or load) the compiled loop once per process, not per thread
            zeroed = not vehicle.filter.payload.travel_from_reference
            estimator = _filter(
                settings.vehicle, settings.allow_unusual, key, zeroed, settings.method
            )
    elif static is not None:
        raise ValueError(
            f"--still-period and --corner-weights apply to --method {_or(compiled_methods())} "
            f"only, not {settings.method!r}"
        )
    elif settings.smooth:
        raise ValueError(
            f"--smooth applies to --method {_or(compiled_methods())} only, not {settings.method!r}"
        )
    else:
        estimator = build(settings.method, vehicle, settings.suspension)
        if method(settings.method).model_choice:
            notes.append(f"{settings.suspension.value} vehicle model (--suspension)")
    with phase(f"filter ({settings.method}{', smoothed' if settings.smooth else ''})"):
        if settings.smooth:
            estimate = estimator.smooth(signals)
            notes.append("loads smoothed over the whole log (Rauch-Tung-Striebel, not causal)")
        else:
            estimate = estimator.run(signals)
    return _log_result(path, vehicle, signals, notes, estimate.named(settings.method))


def _or(names: tuple[str, ...]) -> str:
    """``kf``, ``kf or x``, ``kf, x or y``: the names as a message lists them."""
    return " or ".join(filter(None, (", ".join(names[:-1]), names[-1])))


def _log_result(path: Path, vehicle: Vehicle, signals: Signals, notes, estimate) -> LogResult:
    """A log's estimate with the warnings its signals and loads give."""
    warnings = signal_warnings(signals) + load_warnings(estimate, str(path))
    return LogResult(
        signals=signals, estimate=estimate, vehicle=vehicle, notes=tuple(notes),
        warnings=tuple(warnings),
    )  # fmt: skip


def output_path(log: Path, folder: Path) -> Path:
    """``FOLDER/LOGNAME.estimates.csv``."""
    return folder / f"{log.name}.estimates.csv"


def write_table(frame: pd.DataFrame, path: Path, *, replace: bool = False) -> None:
    """Write a table as CSV or Parquet, by ``path``'s suffix, through a temporary file.

    An existing file is replaced only with ``replace`` (``--force``); pyarrow
    writes it (:func:`~wheelload.estimators.logs.output_files.write_frame`).
    """
    with phase(f"write {path}"):
        write_frame(frame, path, replace=replace)


def log_row(path: Path, result: LogResult) -> dict:
    """One row of the summary table (:func:`~wheelload.studies.pipeline.summary.summary_row`)."""
    signals = result.signals
    header = LogHeader.of(signals, has_reference=signals.reference is not None)
    figures = LoadFigures.of_estimate(result.estimate, signals, str(path))
    return summary_row(str(path), header, figures, result.warnings, result.notes)


#: Logs of more bytes than this run one at a time on the lean path (read in chunks,
#: memory bounded by the chunk) instead of read whole and filtered side by side.
LEAN_BYTES = 32 << 20


def _goes_lean(path: Path, settings: EstimateSettings, lean_bytes: int) -> bool:
    from wheelload.studies.pipeline.lean_estimate import takes_lean_path

    try:
        size = path.stat().st_size
    except OSError:
        return False  # the ordinary reader names the problem
    return takes_lean_path(path, settings) and size > lean_bytes


def lean_row(
    path: Path, settings: EstimateSettings, folder: Path | None, force: bool = False
) -> dict | None:
    """:func:`process_log` on the lean path (``studies/pipeline/lean_estimate.py``): the same
    estimates as :meth:`TwoStageKF.run` to the bit, memory bounded by the chunk; None where
    the chunked reader cannot take the log (nothing written)."""
    from wheelload.studies.pipeline.lean_estimate import estimate_lean

    try:
        out = None if folder is None else output_path(path, folder)
        result = estimate_lean(path, settings, out, force=force)
        if result is None:
            return None
        stream = result.stream
        header = LogHeader.of(stream, has_reference=stream.reference_present is not None)
        figures = LoadFigures.of_digest(result.digest, str(path))
        return summary_row(str(path), header, figures, result.warnings, result.notes)
    except (ValueError, FileNotFoundError) as error:
        return _error_row(path, error)


def process_log(
    path: Path,
    settings: EstimateSettings,
    folder: Path | None,
    force: bool = False,
    lean_bytes: int = LEAN_BYTES,
) -> dict:
    """Estimate one log, write its output into ``folder``; its summary row.

    A log that cannot be used gives a row with its one-line error, so one bad
    file does not stop a fleet. A CSV or Parquet log over ``lean_bytes`` is
    read in chunks (:func:`lean_row`).
    """
    if _goes_lean(path, settings, lean_bytes):
        row = lean_row(path, settings, folder, force)
        if row is not None:
            return row
    try:
        return _written_row(path, estimate_log(path, settings), folder, force)
    except (ValueError, FileNotFoundError) as error:
        return _error_row(path, error)


def _error_row(path: Path, error: Exception) -> dict:
    """The summary row of a log that could not be used: its one-line error."""
    return {"log": str(path), "error": str(error)}


def _written_row(path: Path, result: LogResult, folder: Path | None, force: bool) -> dict:
    """Write a log's estimates into ``folder`` (if given); its summary row."""
    if folder is not None:
        write_table(result.estimate.to_pandas(), output_path(path, folder), replace=force)
    return log_row(path, result)


def process_logs(
    paths: list[Path],
    settings: EstimateSettings,
    folder: Path | None,
    force: bool = False,
    lean_bytes: int = LEAN_BYTES,
) -> list[dict]:
    """:func:`process_log` over a chunk of logs (one task on a worker).

    With the two-stage KF (not smoothed), the chunk's logs are filtered side
    by side in the generated C library's batched step (``estimators/codegen/batched.py``),
    :data:`BATCH` at a time as they are read (a batch is run, written and dropped before
    the next is read: memory bounded by one batch however many logs), a chunk of one log
    too: a log's estimates do not depend
    on its batch, so serial, local processes and Dask give the same bits however
    the logs are split. They equal :meth:`TwoStageKF.run` (a single log's path, the
    compiled loop of the CasADi step) within :data:`BATCHED_TOLERANCE`: the
    generated library evaluates the same equations in another order of
    operations (a few units in the last place, measured by ``wheelload bench
    logs``). A CSV or Parquet log over ``lean_bytes`` runs alone on the lean path
    instead (:func:`lean_row`: memory bounded by the chunk, :meth:`TwoStageKF.run`'s
    numbers to the bit).
    """
    if settings.method != "kf" or settings.smooth:
        return [process_log(path, settings, folder, force, lean_bytes) for path in paths]
    rows: dict[Path, dict] = {}
    pending: dict[tuple[tuple[float, ...] | None, bool], list] = {}
    for path in paths:
        if _goes_lean(path, settings, lean_bytes):
            row = lean_row(path, settings, folder, force)
            if row is not None:
                rows[path] = row
                continue
        try:
            vehicle, signals, notes, static = _prepare_log(path, settings)
        except (ValueError, FileNotFoundError) as error:
            rows[path] = _error_row(path, error)
            continue
        key = None if static is None else tuple(float(f) for f in static)
        zeroed = not vehicle.filter.payload.travel_from_reference
        group = pending.setdefault((key, zeroed), [])
        group.append((path, vehicle, signals, notes))
        if len(group) == BATCH:  # run as soon as a batch is full: memory bounded by it
            del pending[key, zeroed]
            rows.update(_run_batch(settings, folder, force, key, zeroed, group))
    for (key, zeroed), group in pending.items():
        rows.update(_run_batch(settings, folder, force, key, zeroed, group))
    return [rows[path] for path in paths]


def _run_batch(settings, folder, force, key, zeroed, group) -> dict[Path, dict]:
    """The rows of a batch of read logs filtered side by side (:func:`process_logs`)."""
    with _lock:
        kf = _filter(settings.vehicle, settings.allow_unusual, key, zeroed)
    estimates = run_batched(kf, settings.vehicle, [log[2] for log in group])
    return {
        path: _finish_log(path, folder, force, vehicle, signals, notes, estimate)
        for (path, vehicle, signals, notes), estimate in zip(group, estimates, strict=True)
    }


#: Logs filtered side by side at most: a worker holds one batch of logs (each at most
#: :data:`LEAN_BYTES` on disk; longer ones go the lean path) and their estimates at a time,
#: so a folder of any number of logs runs in bounded memory.
BATCH = 16

#: Largest relative difference of a batched estimate from :meth:`TwoStageKF.run`'s
#: (loads and standard deviations): measured at 5e-16 (1.8e-12 N on 5 kN) by
#: ``wheelload bench logs``, allowed with a margin for other logs and compilers.
BATCHED_TOLERANCE = 1e-13


def _finish_log(path, folder, force, vehicle, signals, notes, estimate) -> dict:
    """Warnings, the output file and the summary row of one log estimated in a batch."""
    try:
        return _written_row(
            path, _log_result(path, vehicle, signals, notes, estimate), folder, force
        )
    except (ValueError, FileNotFoundError) as error:
        return _error_row(path, error)


def chunks(paths: list[Path], workers: int) -> list[list[Path]]:
    """About :data:`CHUNKS_PER_WORKER` chunks per worker: few tasks, balanced load."""
    size = max(1, -(-len(paths) // (CHUNKS_PER_WORKER * workers)))
    return [paths[i : i + size] for i in range(0, len(paths), size)]


CHUNKS_PER_WORKER = 8


def run_logs(
    paths: list[Path],
    settings: EstimateSettings,
    folder: Path | None,
    *,
    workers: int = 1,
    dask_address: str | None = None,
    progress: bool = True,
    force: bool = False,
    lean_bytes: int = LEAN_BYTES,
) -> pd.DataFrame:
    """The summary table of many logs (module docstring); rows sorted by log path.

    Logs go to the workers in chunks (:func:`chunks`), so that the cost of a
    task is small beside the logs it carries. Logs over ``lean_bytes`` are read
    in chunks (:func:`process_logs`).
    """
    import pandas as pd
    from tqdm import tqdm

    bar = tqdm(total=len(paths), unit="log", disable=not progress or None)
    rows = []
    if dask_address is not None:
        from distributed import Client
        from distributed import as_completed as dask_completed

        with Client(dask_address) as client:
            threads = max(1, sum(client.nthreads().values()))
            futures = [client.submit(process_logs, chunk, settings, folder, force, lean_bytes,
                                     pure=False)
                       for chunk in chunks(paths, threads)]  # fmt: skip
            for future in dask_completed(futures):
                done = future.result()
                rows += done
                bar.update(len(done))
    elif workers > 1:
        pool = ProcessPoolExecutor(max_workers=workers, initializer=ignore_interrupts)
        try:
            futures = [pool.submit(process_logs, chunk, settings, folder, force, lean_bytes)
                       for chunk in chunks(paths, workers)]  # fmt: skip
            for future in as_completed(futures):
                done = future.result()
                rows += done
                bar.update(len(done))
        finally:  # on Ctrl-C or SIGTERM: the chunks not started are dropped
            pool.shutdown(cancel_futures=True)
    else:
        for chunk in chunks(paths, 1):
            done = process_logs(chunk, settings, folder, force, lean_bytes)
            rows += done
            bar.update(len(done))
    bar.close()
    columns = list(dict.fromkeys(key for row in rows for key in row))
    table = pd.DataFrame(rows, columns=columns).sort_values("log", ignore_index=True)
    if "error" in table.columns:
        table["error"] = table["error"].fillna("")
    return table
