"""Identification's time and peak memory against log length: dense against chunked.

A lap (a plant log with reference loads: by default a simulated Nordschleife
lap, ``--quick`` the bundled example log) is tiled 1, 4, 16 times (time
kept increasing) into a Parquet log; each case reads that log
(:func:`~wheelload.estimators.identification.data.read_drive`, chunk by chunk)
and fits it in a child process of its own, whose peak resident memory
(``VmHWM``, where ``/proc`` tells it; else ``os.wait4``'s figure) is that of
the read and the fit alone (numpy and CasADi allocate outside
``tracemalloc``'s sight). The chunked fits are compared with the dense fit of
the same length: the largest relative difference of the fitted values and
standard errors.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators.identification import default_model, drive_gates, identify, read_drive
from wheelload.estimators.identification.fit import FitLoss, FitPath, FitSettings
from wheelload.models import ModelParameters, example_vehicle_path, load_vehicle

#: Skip a dense fit whose peak, extrapolated linearly from one lap, would pass this [MB].
DENSE_LIMIT = 8000.0


@dataclass(frozen=True, kw_only=True)
class Case:
    path: FitPath
    loss: FitLoss
    instrumental: bool


def write_laps(lap: Path, laps: int, path: Path) -> None:
    """``lap`` (CSV or Parquet) repeated ``laps`` times into the Parquet log ``path``, time
    kept increasing; one lap in memory at a time."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    parquet = lap.suffix.lower() in (".parquet", ".pq")
    frame = (pd.read_parquet(lap) if parquet else pd.read_csv(lap, comment="#")).astype(float)
    t = frame["t"].to_numpy()
    span = t[-1] - t[0] + float(np.median(np.diff(t)))
    schema = pa.schema([(str(name), pa.float64()) for name in frame.columns])
    with pq.ParquetWriter(str(path), schema) as writer:
        for k in range(laps):
            frame["t"] = t + k * span
            writer.write_table(pa.Table.from_pandas(frame, schema=schema, preserve_index=False))


def _own_peak() -> float | None:
    """This process's peak resident memory [MB] (``VmHWM``), None without ``/proc``."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            kb = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
    except OSError:
        return None
    return int(kb) / 1024.0


def fit_case(log: Path, case: Case) -> dict:
    """One case (run in the child): the read and fit times, the fitted values and errors."""
    vehicle = load_vehicle(example_vehicle_path())
    p = ModelParameters.from_vehicle(vehicle)
    model = default_model()
    start = time.perf_counter()
    data = (read_drive(log, model.channel_names(), model.optional),)
    read = time.perf_counter() - start
    model = default_model(drive_gates(p, data))
    settings = FitSettings(path=case.path, loss=case.loss, instrumental=case.instrumental)
    start = time.perf_counter()
    result = identify(model, data, p, settings)
    return {
        "read_seconds": read,
        "seconds": time.perf_counter() - start,
        "samples": len(data[0]),
        "free": list(result.free),
        "value": result.value.tolist(),
        "std": result.std_error.tolist(),
        "peak_mb": _own_peak(),
    }


def child() -> None:
    """``python -c`` entry: argv = log, path, loss, instrumental; prints JSON."""
    log, path, loss, instrumental = sys.argv[1:5]
    case = Case(path=FitPath(path), loss=FitLoss(loss), instrumental=instrumental == "1")
    print(json.dumps(fit_case(Path(log), case)))


def run_child(log: Path, case: Case) -> tuple[dict, float]:
    """The case on ``log`` in a child process: its result and its peak resident memory [MB]."""
    command = [
        sys.executable,
        "-c",
        "from wheelload.studies.bench.identification import child; child()",
        str(log),
        case.path.value,
        case.loss.value,
        "1" if case.instrumental else "0",
    ]
    with tempfile.TemporaryFile() as output:
        process = subprocess.Popen(command, stdout=output, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        error = process.stderr.read().decode()
        process.stderr.close()
        if process.returncode:
            raise RuntimeError(f"identification child failed: {error.strip().splitlines()[-1]}")
        output.seek(0)
        result = json.loads(output.read().decode())
    peak = result.pop("peak_mb")
    return result, usage.ru_maxrss / 1024.0 if peak is None else peak


def difference(a: dict, b: dict) -> float:
    """Largest relative difference of the fitted values and standard errors."""
    if a["free"] != b["free"]:
        return float("inf")
    free = a["free"]
    worst = 0.0
    for key in ("value", "std"):
        x, y = np.asarray(a[key])[free], np.asarray(b[key])[free]
        worst = max(worst, float(np.max(np.abs(x - y) / np.abs(x), initial=0.0)))
    return worst


def bench(
    log: Path, laps: tuple[int, ...], loss: FitLoss, instrumental: bool, repeat: int, folder: Path
) -> list[dict]:
    """Rows of the table: laps, samples, path, min/median/max seconds (fit, and read),
    peak MB, difference; the tiled logs are written into ``folder``."""
    table = []
    dense_per_lap = None
    for count in laps:
        tiled = folder / f"{log.stem}_{count}_laps.parquet"
        write_laps(log, count, tiled)
        dense = None
        for path in (FitPath.DENSE, FitPath.CHUNKED):
            row = {"laps": count, "path": path.value}
            if path is FitPath.DENSE and dense_per_lap and dense_per_lap * count > DENSE_LIMIT:
                row["skipped"] = f"dense would need about {dense_per_lap * count:.0f} MB"
                table.append(row)
                continue
            case = Case(path=path, loss=loss, instrumental=instrumental)
            runs = [run_child(tiled, case) for _ in range(repeat)]
            seconds = [result["seconds"] for result, _ in runs]
            reads = [result["read_seconds"] for result, _ in runs]
            peak = max(mb for _, mb in runs)
            result = runs[0][0]
            row |= {
                "samples": result["samples"],
                "seconds": (min(seconds), statistics.median(seconds), max(seconds)),
                "read_seconds": (min(reads), statistics.median(reads), max(reads)),
                "peak_mb": peak,
            }
            if path is FitPath.DENSE:
                dense = result
                dense_per_lap = max(dense_per_lap or 0.0, peak / count)
            elif dense is not None:
                row["difference"] = difference(dense, result)
            table.append(row)
        tiled.unlink()
    return table
