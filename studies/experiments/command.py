"""``wheelload study NAME --out DIR`` for the experiments (every name but ``mhe-vs-kf``).

The output folder is locked before any work
(:mod:`~wheelload.studies.experiments.runs.folder_lock`), so a second study into it
refuses at once.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from wheelload.estimators import SuspensionModel
from wheelload.models import example_vehicle_path
from wheelload.studies.commands.options import add_suspension_option
from wheelload.studies.experiments.catalog import NAMES, run_study
from wheelload.studies.experiments.runs.cache import ResultCache
from wheelload.studies.experiments.runs.context import Context, Outputs, Settings
from wheelload.studies.experiments.runs.folder_lock import folder_lock
from wheelload.studies.experiments.runs.runner import Runner


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The experiments' options on the ``study`` sub-parser (``--quick``, ``--force`` and
    ``--out`` are the study command's own, shared with mhe-vs-kf)."""
    parser.add_argument("--workers", type=int, default=2, help="local processes (default 2)")
    parser.add_argument("--dask", metavar="ADDRESS", help="run on this Dask scheduler")
    parser.add_argument("--cache", help="cache folder (default DIR/.cache)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_suspension_option(parser)


def run(args: argparse.Namespace) -> int:
    """Run study ``args.name`` into ``args.out``; print what was computed and cached."""
    if args.name not in NAMES:
        raise ValueError(f"unknown study '{args.name}'; choose from mhe-vs-kf, {', '.join(NAMES)}")
    if args.out is None:
        raise ValueError(f"study {args.name} needs --out DIR (a folder for tables and figures)")
    if args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: exists and is not a folder; give a folder to --out")
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out):  # before any work: a second study into ``out`` refuses at once
        return _run(args, out)


def _run(args: argparse.Namespace, out: Path) -> int:
    vehicle_path = Path(args.vehicle or example_vehicle_path())
    if not vehicle_path.is_file():
        raise ValueError(f"{vehicle_path}: no such vehicle file (--vehicle)")
    if args.dask is not None:
        _check_scheduler(args.dask)
    settings = Settings(
        vehicle_path=vehicle_path,
        vehicles_folder=example_vehicle_path().parent,
        quick=args.quick,
        suspension=SuspensionModel.parse(args.suspension),
    )
    runner = Runner(
        cache=ResultCache(folder=Path(args.cache) if args.cache else out / ".cache"),
        workers=args.workers,
        dask_address=args.dask,
        progress=not args.no_progress,
    )
    outputs = Outputs(folder=out, force=args.force)
    start = time.perf_counter()
    with runner:
        run_study(args.name, Context(settings=settings, runner=runner, outputs=outputs))
    print(
        f"study {args.name}: {runner.computed} jobs computed, {runner.cached} from the cache, "
        f"{time.perf_counter() - start:.1f} s; {len(outputs.written)} files in {out}"
    )
    return 0


def _check_scheduler(address: str) -> None:
    """A one-line error when no Dask scheduler answers at ``address``."""
    from distributed import Client

    try:
        Client(address, timeout=10).close()
    except (OSError, TimeoutError, ValueError) as error:
        raise ValueError(
            f"--dask {address}: no Dask scheduler answers ({type(error).__name__}); "
            "start one (dask scheduler) or give its address as tcp://HOST:PORT"
        ) from None
