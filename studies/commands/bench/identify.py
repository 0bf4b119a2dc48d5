"""``wheelload bench identify``: identification's time and peak memory against log length,
the dense fit (all regressors in memory) against the chunked one (the default)."""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from wheelload.estimators.identification.fit import FitLoss
from wheelload.models import example_vehicle_path
from wheelload.studies.bench.identification import DENSE_LIMIT, bench
from wheelload.studies.drive.scenario_log import write_log
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.pipeline.example_log import example_log_path

#: Relative difference of values and standard errors below which the fits are called equal.
EQUAL = 1e-9


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("identify")
    parser.add_argument(
        "--log",
        help="one lap: a plant log with fz_* reference loads (default: a Nordschleife lap "
        "simulated into a temporary folder, about 90 s; --quick: the bundled example log)",
    )
    parser.add_argument("--laps", default="1,4,16", help="tilings of the lap (default 1,4,16)")
    parser.add_argument(
        "--robust", choices=("huber", "soft-l1"), help="robust loss instead of least squares"
    )
    parser.add_argument("--instrumental", action="store_true", help="two-stage least squares")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each case (default 1)")
    parser.add_argument(
        "--quick", action="store_true", help="the bundled example log tiled 1 and 4 times"
    )
    parser.set_defaults(handler=run)


def _laps(text: str) -> tuple[int, ...]:
    try:
        laps = tuple(int(k) for k in text.split(","))
    except ValueError:
        raise ValueError(f"--laps '{text}': give whole numbers, e.g. 1,4,16") from None
    if not laps or min(laps) < 1:
        raise ValueError(f"--laps '{text}': give positive whole numbers, e.g. 1,4,16")
    return laps


def run(args: argparse.Namespace) -> int:
    laps = (1, 4) if args.quick else _laps(args.laps)
    if args.repeat < 1:
        raise ValueError("--repeat: give at least 1")
    loss = FitLoss(args.robust) if args.robust else FitLoss.LINEAR
    with tempfile.TemporaryDirectory() as folder:
        if args.log:
            log = Path(args.log)
            if not log.exists():
                raise ValueError(f"--log {log}: no such file")
        elif args.quick:
            log = example_log_path()
        else:
            log = Path(folder) / "nordschleife.parquet"
            result = run_scenario("nordschleife", example_vehicle_path())
            write_log(result.log, log, result.metadata)
        table = bench(log, laps, loss, args.instrumental, args.repeat, Path(folder))
    print(
        f"identification of {log.name} tiled {', '.join(map(str, laps))} times "
        f"({loss.value} loss{', instruments' if args.instrumental else ''}); "
        f"fit and read seconds min/median/max of {args.repeat}, peak resident memory of the "
        "child process (read and fit)"
    )
    print(
        f"{'laps':>5} {'samples':>9} {'path':>8} {'fit seconds':>26} {'read seconds':>20} "
        f"{'peak MB':>9}  equal"
    )
    for row in table:
        if "skipped" in row:
            print(f"{row['laps']:>5} {'':>9} {row['path']:>8}  skipped: {row['skipped']}")
            continue
        seconds = "/".join(f"{s:.2f}" for s in row["seconds"])
        reads = "/".join(f"{s:.2f}" for s in row["read_seconds"])
        equal = ""
        if "difference" in row:
            verdict = "yes" if row["difference"] <= EQUAL else "NO"
            equal = f"{verdict} (max rel. difference {row['difference']:.1e})"
        print(
            f"{row['laps']:>5} {row['samples']:>9} {row['path']:>8} {seconds:>26} {reads:>20} "
            f"{row['peak_mb']:>9.0f}  {equal}"
        )
    print(f"dense fits skipped where one lap's peak times the laps passes {DENSE_LIMIT:.0f} MB")
    return 0
