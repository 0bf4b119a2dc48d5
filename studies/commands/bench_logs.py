"""``wheelload bench logs``: throughput of many logs, serial, local processes and Dask.

Writes ``--logs`` short plant logs (windows of ``--samples`` samples of the
bundled plant log, each starting elsewhere) into a temporary folder and runs
``wheelload estimate`` on them serially (1 worker), on local processes
(``--workers``) and on a ``distributed.LocalCluster`` of the same size;
prints samples per second (min / median / max of ``--repeat`` runs), the
ratio to the serial run, and whether each summary equals the serial one.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import pandas as pd

from wheelload.models import example_vehicle_path
from wheelload.studies.batch import EstimateSettings, expand_logs, run_logs


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("logs", help="many logs: serial, local processes, Dask")
    parser.add_argument("--logs", type=int, default=200, help="number of logs (default 200)")
    parser.add_argument("--samples", type=int, default=300, help="samples per log (default 300)")
    parser.add_argument("--workers", type=int, nargs="+", default=[2], help="worker counts")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3)")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster")
    parser.set_defaults(handler=run)


def _write_logs(folder: Path, count: int, samples: int) -> list[Path]:
    from wheelload.studies.commands.estimate import example_log_path

    source = pd.read_csv(example_log_path())
    span = len(source) - samples
    if span < 1:
        raise ValueError(f"--samples must be below {len(source)}")
    for k in range(count):
        start = (k * 37) % span
        source.iloc[start : start + samples].to_csv(folder / f"log{k:04d}.csv", index=False)
    return expand_logs([str(folder)])


def _time(runs: int, call) -> tuple[list[float], pd.DataFrame]:
    times, table = [], None
    for _ in range(runs):
        start = time.perf_counter()
        table = call()
        times.append(time.perf_counter() - start)
    return times, table


def _line(label: str, samples: int, times: list[float], serial: float | None, same: str) -> str:
    rates = sorted(samples / t for t in times)
    median = statistics.median(rates)
    ratio = f"{median / serial:5.2f}" if serial else f"{1.0:5.2f}"
    return (f"{label:28s} {rates[0]:10.0f} {median:10.0f} {rates[-1]:10.0f} {ratio:>8s} "
            f"{same:>8s}")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    settings = EstimateSettings(vehicle=example_vehicle_path())
    with tempfile.TemporaryDirectory() as folder:
        paths = _write_logs(Path(folder), args.logs, args.samples)
        total = args.logs * args.samples
        print(f"{args.logs} logs x {args.samples} samples (windows of the bundled plant log); "
              f"samples/s over {args.repeat} runs")  # fmt: skip
        print(f"{'run':28s} {'min':>10s} {'median':>10s} {'max':>10s} {'x serial':>8s} "
              f"{'same':>8s}")  # fmt: skip
        run_logs(paths[:2], settings, None, progress=False)  # build the compiled loop once
        times, serial = _time(args.repeat, lambda: run_logs(paths, settings, None, progress=False))
        serial_rate = statistics.median(total / t for t in times)
        print(_line("serial (1 worker)", total, times, None, "-"))
        for workers in args.workers:
            times, table = _time(args.repeat, lambda w=workers: run_logs(
                paths, settings, None, workers=w, progress=False))  # fmt: skip
            same = "yes" if table.equals(serial) else "NO"
            print(_line(f"local processes ({workers})", total, times, serial_rate, same))
            if args.no_dask:
                continue
            from distributed import LocalCluster

            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster:  # fmt: skip
                run_logs(
                    paths[: 2 * workers],
                    settings,
                    None,
                    dask_address=cluster.scheduler_address,
                    progress=False,
                )  # warm up
                times, table = _time(args.repeat, lambda a=cluster.scheduler_address: run_logs(
                    paths, settings, None, dask_address=a, progress=False))  # fmt: skip
            same = "yes" if table.equals(serial) else "NO"
            print(_line(f"dask LocalCluster ({workers})", total, times, serial_rate, same))
    return 0
