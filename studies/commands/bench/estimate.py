"""``wheelload bench estimate``: ``wheelload estimate --out`` end to end, and its cold start.

Each run is a fresh ``wheelload`` process (its wall and CPU time from ``wait4``,
its peak resident memory its own ``VmHWM``), on a log made by repeating the bundled example log
(time kept increasing; written as Parquet in row groups). Three ways, in turn
so that all meet the same machine load, ``--repeat`` times each:

- ``lean .csv`` and ``lean .parquet``: the default, the chunked whole-log path
  (``estimators/kf/log_stream.py``), the estimates written as CSV or as Parquet
  (on a writer thread overlapping the compiled loop); their ratio, pair by pair,
  is what CSV costs over Parquet;
- ``in-memory``: ``--in-memory``, the whole log read into memory (pandas),
  ``TwoStageKF.run``, ``Estimate.to_pandas`` written by pyarrow (as CSV).

Beside them, in this process, the filter alone: the compiled column loop over the log's
first 1e6 samples held in memory (no read, no write, no summary), per sample; each
way's CPU time per sample over it is what reading, checking, summarising and writing
cost on top of the compiled step.

``--example`` cold (a fresh, empty build folder: the compiled loop is built)
and warm (the same folder again). Figures: min / median / max of wall time,
CPU time (user + system: on a shared machine the wall time includes waiting
for a core) and peak resident memory.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("estimate")
    parser.add_argument(
        "--samples",
        type=float,
        nargs="*",
        default=[1e6, 1e7],
        help="log sizes (default 1e6 1e7; none: only the --example cold start)",
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3)")
    parser.add_argument(
        "--in-memory-up-to",
        type=float,
        default=1e7,
        help="measure the in-memory path only up to this size (default 1e7)",
    )
    parser.set_defaults(handler=run)


def write_tiled_log(path: Path, samples: int) -> None:
    """A Parquet log of ``samples`` rows: the example log repeated, time increasing."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    from wheelload.studies.pipeline.example_log import example_log_path

    base = pd.read_csv(example_log_path())
    rate = round(1.0 / float(np.median(np.diff(base["t"].to_numpy()))))  # Hz
    block = 1 << 20
    reps = -(-block // len(base))
    tiled = {name: np.tile(base[name].to_numpy(float), reps)[:block] for name in base.columns}
    with pq.ParquetWriter(str(path), pa.schema([(n, pa.float64()) for n in base.columns])) as w:
        for start in range(0, samples, block):
            n = min(block, samples - start)
            columns = dict(tiled)
            columns["t"] = (start + np.arange(block)) / rate
            w.write_table(pa.table({k: v[:n] for k, v in columns.items()}))


#: ``python -c`` running the ``wheelload`` command and printing, at its exit, its own peak
#: resident memory (``VmHWM``: the ``wait4`` figure of a child includes the memory of the
#: process it was started from, this benchmark with its tiled log).
_PEAK_REPORTING = """
import atexit, runpy, sys
def _peak():
    with open("/proc/self/status") as status:
        kb = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
    print(f"peak-kB {kb}", file=sys.stderr)
atexit.register(_peak)
sys.argv[0] = "wheelload"
runpy.run_module("wheelload.studies.cli", run_name="__main__")
"""


def _timed(command: list[str], env: dict | None = None) -> tuple[float, float, float]:
    """Wall time [s], peak resident memory [MB] and CPU time [s] of a child process.

    The peak is the child's own (``VmHWM``) where ``/proc`` tells it, else ``wait4``'s.
    """
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    stderr = child.stderr.read().decode() if child.stderr else ""
    if child.stderr:
        child.stderr.close()
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {stderr.strip()}")
    reported = [line.split()[1] for line in stderr.splitlines() if line.startswith("peak-kB ")]
    peak = int(reported[-1]) if reported else usage.ru_maxrss
    return wall, peak / 1024.0, usage.ru_utime + usage.ru_stime


def _spread(values: list[float], fmt: str) -> str:
    return " / ".join(format(v, fmt) for v in (min(values), statistics.median(values), max(values)))


def run(args: argparse.Namespace) -> int:
    from wheelload.models import example_vehicle_path

    wheelload = [sys.executable, "-c", _PEAK_REPORTING]
    if not Path("/proc/self/status").exists():
        wheelload = [sys.executable, "-m", "wheelload.studies.cli"]
    vehicle = str(example_vehicle_path())
    print(f"wheelload estimate --out, {os.cpu_count()} cores; min / median / max of "
          f"{args.repeat} runs; each a fresh process")  # fmt: skip
    print(
        f"  load average {_load()} at the start; Python bytecode "
        f"{'not written (PYTHONDONTWRITEBYTECODE)' if sys.flags.dont_write_bytecode else 'cached'}"
    )
    with tempfile.TemporaryDirectory() as folder:
        for size in args.samples:
            n = int(size)
            log = Path(folder) / f"log_{n}.parquet"
            write_tiled_log(log, n)
            ways = {"lean .csv": (".csv", []), "lean .parquet": (".parquet", [])}
            if n <= args.in_memory_up_to:
                ways["in-memory"] = (".csv", ["--in-memory"])
            figures: dict[str, list[tuple[float, float, float]]] = {way: [] for way in ways}
            sizes = {}
            for _ in range(args.repeat):
                for way, (suffix, extra) in ways.items():
                    out = Path(folder) / f"out{suffix}"
                    command = [*wheelload, "estimate", str(log), "--vehicle", vehicle,
                               "--out", str(out), "--force", *extra]  # fmt: skip
                    figures[way].append(_timed(command))
                    sizes[suffix] = out.stat().st_size / 1e6
                    out.unlink()
            print(f"  {n:>10} samples ({log.stat().st_size / 1e6:.0f} MB Parquet in; out "
                  f"{sizes['.csv']:.0f} MB CSV, {sizes['.parquet']:.0f} MB Parquet):")  # fmt: skip
            for way, runs in figures.items():
                walls, peaks, cpu = ([r[k] for r in runs] for k in range(3))
                print(f"    {way:13s} wall {_spread(walls, '7.2f')} s   "
                      f"cpu {_spread(cpu, '7.2f')} s"
                      f"   peak RSS {_spread(peaks, '6.0f')} MB")  # fmt: skip
            loop = _loop_per_sample(log, vehicle, args.repeat)
            print(f"    compiled loop on chunks in memory (first {min(n, LOOP_SAMPLES)} samples): "
                  f"{_spread([v * 1e6 for v in loop], '.3f')} us per sample")  # fmt: skip
            step = statistics.median(loop)
            for way in ("lean .csv", "lean .parquet"):
                cpu = [r[2] / n / step for r in figures[way]]
                wall = [r[0] / n / step for r in figures[way]]
                print(f"    {way} per sample / compiled loop: cpu {_spread(cpu, '.2f')}   "
                      f"wall {_spread(wall, '.2f')}")  # fmt: skip
            pairs = list(zip(figures["lean .csv"], figures["lean .parquet"], strict=True))
            print(f"    CSV / Parquet, pair by pair: wall "
                  f"{_spread([c[0] / p[0] for c, p in pairs], '.2f')}   cpu "
                  f"{_spread([c[2] / p[2] for c, p in pairs], '.2f')}")  # fmt: skip
            if "in-memory" in figures:
                lean = statistics.median(r[0] for r in figures["lean .csv"])
                whole = statistics.median(r[0] for r in figures["in-memory"])
                lean_mb = statistics.median(r[1] for r in figures["lean .csv"])
                whole_mb = statistics.median(r[1] for r in figures["in-memory"])
                print(f"    lean (CSV) is {whole / lean:.1f}x faster, {whole_mb / lean_mb:.1f}x "
                      "less memory than in-memory (medians)")  # fmt: skip
        cold, warm = [], []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as build:
                env = dict(os.environ, TMPDIR=build)
                command = [*wheelload, "estimate", "--example"]
                cold.append(_timed(command, env))
                warm.append(_timed(command, env))
        for name, runs in (("cold (empty build folder)", cold), ("warm", warm)):
            walls, cpu = [r[0] for r in runs], [r[2] for r in runs]
            print(f"  estimate --example {name:26s} wall {_spread(walls, '6.2f')} s   "
                  f"cpu {_spread(cpu, '6.2f')} s")  # fmt: skip
    print(f"  load average {_load()} at the end")
    return 0


#: Samples of the log the compiled loop is timed on (held in memory).
LOOP_SAMPLES = 1_000_000


def _loop_per_sample(log: Path, vehicle: str, repeat: int) -> list[float]:
    """CPU seconds per sample of the KF's compiled column loop (``LogStream.chunks``) over
    the log's first :data:`LOOP_SAMPLES` samples, read into memory first."""
    from wheelload.estimators.kf.log_stream import LogScan
    from wheelload.estimators.logs.readers.chunks import read_chunks
    from wheelload.estimators.registry import build
    from wheelload.models import load_vehicle

    scan = LogScan(log, rows=1 << 16, still_period=None, wiring_checks=False)
    chunks, count = [], 0
    for chunk in read_chunks(log, list(scan.names), rows=scan.rows):
        chunk = {name: values[: LOOP_SAMPLES - count] for name, values in chunk.items()}
        scan.add(chunk)
        chunks.append(chunk)
        count += len(chunk["t"])
        if count >= LOOP_SAMPLES:
            break
    stream = scan.finish()
    kf = build("kf", load_vehicle(vehicle))
    for _ in stream.chunks(kf, source=iter(chunks[:1])):  # the loop built, warm
        pass
    times = []
    for _ in range(repeat):
        start = time.process_time()
        for _ in stream.chunks(kf, source=iter(chunks)):
            pass
        times.append((time.process_time() - start) / count)
    return times


def _load() -> str:
    """The 1, 5 and 15 min load averages (``uptime``)."""
    return " ".join(f"{value:.2f}" for value in os.getloadavg())
