"""``wheelload bench logs``: throughput of many logs, serial, local processes and Dask.

Writes ``--logs`` short plant logs (windows of ``--samples`` samples of the
bundled plant log, each starting elsewhere) into a temporary folder and runs
``wheelload estimate`` on them serially (1 worker), on local processes
(``--workers``) and on a ``distributed.LocalCluster`` of the same size;
prints samples per second (min / median / max of ``--repeat`` runs, the
variants run in turn so that each meets the same machine load), the ratio to
the serial run, and how each summary compares with the serial one: ``same``
(bit for bit), ``within`` (every number within
:data:`~wheelload.studies.pipeline.batch.BATCHED_TOLERANCE` relative to its column's
largest magnitude) or ``NO``, with the largest difference. A last line
compares the serial summary with single runs of each log
(:meth:`TwoStageKF.run`, which the batched step equals within that tolerance).
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import tempfile
import time
from pathlib import Path

import pandas as pd

from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.batch import (
    BATCHED_TOLERANCE,
    EstimateSettings,
    expand_logs,
    process_log,
    run_logs,
)
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.summary_compare import compare


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("logs")
    parser.add_argument(
        "--log-count", dest="logs", type=int, default=200, metavar="N",
        help="number of logs (default 200)",
    )  # fmt: skip
    parser.add_argument("--samples", type=int, default=300, help="samples per log (default 300)")
    parser.add_argument("--workers", type=int, nargs="+", default=[2], help="worker counts")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3)")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster")
    parser.set_defaults(handler=run)


def _write_logs(folder: Path, count: int, samples: int) -> list[Path]:
    source = pd.read_csv(example_log_path())
    span = len(source) - samples
    if span < 1:
        raise ValueError(f"--samples must be below {len(source)}")
    for k in range(count):
        start = (k * 37) % span
        source.iloc[start : start + samples].to_csv(folder / f"log{k:04d}.csv", index=False)
    return expand_logs([str(folder)])


def _line(label: str, samples: int, times: list[float], serial: float | None, same) -> str:
    rates = sorted(samples / t for t in times)
    median = statistics.median(rates)
    ratio = f"{median / serial:5.2f}" if serial else f"{1.0:5.2f}"
    verdict, difference = same
    return (f"{label:28s} {rates[0]:10.0f} {median:10.0f} {rates[-1]:10.0f} {ratio:>8s} "
            f"{verdict:>8s} {difference:12.2e}")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    settings = EstimateSettings(vehicle=example_vehicle_path())
    with tempfile.TemporaryDirectory() as folder, contextlib.ExitStack() as stack:
        paths = _write_logs(Path(folder), args.logs, args.samples)
        total = args.logs * args.samples
        variants = {"serial (1 worker)": {}}
        for workers in args.workers:
            variants[f"local processes ({workers})"] = {"workers": workers}
            if not args.no_dask:
                from distributed import LocalCluster

                # ":0": the dashboard on a free port (None would still try 8787,
                # dask/distributed#8136), so two benches or a user's cluster do not collide.
                cluster = stack.enter_context(LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True,
                    dashboard_address=":0"))  # fmt: skip
                variants[f"dask LocalCluster ({workers})"] = {
                    "dask_address": cluster.scheduler_address
                }
        for options in variants.values():  # warm up: imports and the compiled loop
            run_logs(paths[: 4 * args.workers[-1]], settings, None, progress=False, **options)
        times: dict[str, list[float]] = {name: [] for name in variants}
        tables = {}
        for _ in range(args.repeat):  # round robin: every variant meets the same load
            for name, options in variants.items():
                start = time.perf_counter()
                tables[name] = run_logs(paths, settings, None, progress=False, **options)
                times[name].append(time.perf_counter() - start)
        serial_name = next(iter(variants))
        serial_rate = statistics.median(total / t for t in times[serial_name])
        print(f"{args.logs} logs x {args.samples} samples (windows of the bundled plant log); "
              f"samples/s over {args.repeat} runs, run in turn")  # fmt: skip
        print(f"{'run':28s} {'min':>10s} {'median':>10s} {'max':>10s} {'x serial':>8s} "
              f"{'summary':>8s} {'max |diff|':>12s}")  # fmt: skip
        for name in variants:
            same = compare(tables[name], tables[serial_name])
            ratio = None if name == serial_name else serial_rate
            print(_line(name, total, times[name], ratio, same))
        single = pd.DataFrame([process_log(path, settings, None) for path in paths])
        verdict, difference = compare(
            tables[serial_name], single.sort_values("log", ignore_index=True)
        )
        print(f"serial against single runs (TwoStageKF.run per log): {verdict}, max |diff| "
              f"{difference:.2e} (tolerance {BATCHED_TOLERANCE:.0e} relative)")  # fmt: skip
    return 0
