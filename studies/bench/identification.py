"""Identification's time and peak memory against log length: dense against chunked.

A lap (a plant log with reference loads: by default a simulated Nordschleife
lap, ``--quick`` the bundled example log) is tiled 1, 4, 16 times (time
kept increasing); each fit runs in its own child process so that its peak
memory is the operating system's figure for that process alone
(``os.wait4``: numpy and CasADi allocate outside ``tracemalloc``'s sight).
The chunked fits are compared with the dense fit of the same length: the
largest relative difference of the fitted values and standard errors.
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
from wheelload.estimators.identification.data import DataSet
from wheelload.estimators.identification.fit import FitLoss, FitPath, FitSettings
from wheelload.models import ModelParameters, example_vehicle_path, load_vehicle

#: Skip a dense fit whose peak, extrapolated linearly from one lap, would pass this [MB].
DENSE_LIMIT = 8000.0


@dataclass(frozen=True, kw_only=True)
class Case:
    laps: int
    path: FitPath
    loss: FitLoss
    instrumental: bool


def tiled(data: DataSet, laps: int) -> DataSet:
    """``data`` repeated ``laps`` times, time kept increasing."""
    dt = float(np.median(np.diff(data.t)))
    span = data.t[-1] - data.t[0] + dt
    return DataSet(
        kind=data.kind,
        source=data.source,
        t=np.concatenate([data.t + k * span for k in range(laps)]),
        signals={name: np.tile(v, (laps, 1)) for name, v in data.signals.items()},
        target=np.tile(data.target, (laps, 1)),
        rows=data.rows,
        absent=data.absent,
    )


def fit_case(log: Path, case: Case) -> dict:
    """One fit (run in the child): time and the fitted values and errors."""
    vehicle = load_vehicle(example_vehicle_path())
    p = ModelParameters.from_vehicle(vehicle)
    model = default_model()
    data = (tiled(read_drive(log, model.channel_names(), model.optional), case.laps),)
    model = default_model(drive_gates(p, data))
    settings = FitSettings(path=case.path, loss=case.loss, instrumental=case.instrumental)
    start = time.perf_counter()
    result = identify(model, data, p, settings)
    return {
        "seconds": time.perf_counter() - start,
        "samples": len(data[0]),
        "free": list(result.free),
        "value": result.value.tolist(),
        "std": result.std_error.tolist(),
    }


def child() -> None:
    """``python -c`` entry: argv = log, laps, path, loss, instrumental; prints JSON."""
    log, laps, path, loss, instrumental = sys.argv[1:6]
    case = Case(
        laps=int(laps), path=FitPath(path), loss=FitLoss(loss), instrumental=instrumental == "1"
    )
    print(json.dumps(fit_case(Path(log), case)))


def run_child(log: Path, case: Case) -> tuple[dict, float]:
    """The fit of ``case`` in a child process: its result and its peak resident memory [MB]."""
    command = [
        sys.executable,
        "-c",
        "from wheelload.studies.bench.identification import child; child()",
        str(log),
        str(case.laps),
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
        return json.loads(output.read().decode()), usage.ru_maxrss / 1024.0


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
    log: Path, laps: tuple[int, ...], loss: FitLoss, instrumental: bool, repeat: int
) -> list[dict]:
    """Rows of the table: laps, samples, path, min/median/max seconds, peak MB, difference."""
    table = []
    dense_per_lap = None
    for count in laps:
        dense = None
        for path in (FitPath.DENSE, FitPath.CHUNKED):
            row = {"laps": count, "path": path.value}
            if path is FitPath.DENSE and dense_per_lap and dense_per_lap * count > DENSE_LIMIT:
                row["skipped"] = f"dense would need about {dense_per_lap * count:.0f} MB"
                table.append(row)
                continue
            case = Case(laps=count, path=path, loss=loss, instrumental=instrumental)
            runs = [run_child(log, case) for _ in range(repeat)]
            seconds = [result["seconds"] for result, _ in runs]
            peak = max(mb for _, mb in runs)
            result = runs[0][0]
            row |= {
                "samples": result["samples"],
                "seconds": (min(seconds), statistics.median(seconds), max(seconds)),
                "peak_mb": peak,
            }
            if path is FitPath.DENSE:
                dense = result
                dense_per_lap = max(dense_per_lap or 0.0, peak / count)
            elif dense is not None:
                row["difference"] = difference(dense, result)
            table.append(row)
    return table
