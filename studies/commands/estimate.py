"""``wheelload estimate``: run an estimator (default: the two-stage KF) on one log or many.

One log: a summary on screen, ``--out`` estimates CSV, ``--plot`` figure. A CSV or
Parquet log with the KF runs on the lean whole-log path (``estimators/kf/log_stream.py``:
read, filtered, written and summarised in chunks, memory bounded by the chunk, the
numbers of the in-memory run to the bit); ``--in-memory`` reads it whole.
Many logs (a folder, a glob, or several names): ``--out FOLDER`` gets one
``LOG.estimates.csv`` per log and ``summary.csv``; logs run on ``--workers``
local processes or on a Dask cluster (``--dask ADDRESS``), with a progress bar.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.estimators import SuspensionModel
from wheelload.estimators.logs.output_files import check_figure_suffix, check_outputs, table_format
from wheelload.estimators.registry import method
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    add_suspension_option,
    quiet,
    show_progress,
    vehicle_file,
)
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.lean_estimate import estimate_lean, takes_lean_path
from wheelload.studies.pipeline.log_settings import EstimateSettings, expand_logs
from wheelload.studies.pipeline.summary import MESSAGE_SEPARATOR, LogHeader, summary, summary_text

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True, many_logs=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "estimate",
        help=CATALOG["estimate"].summary,
    )
    parser.add_argument(
        "log", nargs="*", help="log file(s), folder(s) or glob(s): .csv .parquet .mf4 .erg"
    )
    parser.add_argument(
        "--vehicle", metavar="FILE", help="vehicle TOML file (required with a log of yours)"
    )
    parser.add_argument(
        "--example",
        action="store_true",
        help="use the bundled example log and vehicle (the sports car; --vehicle: another)",
    )
    parser.add_argument(
        "--method", default="kf", help="estimator name (see `wheelload methods`; default kf)"
    )
    parser.add_argument(
        "--out",
        metavar="FILE|DIR",
        help="file for one log: the estimates as .parquet or .csv (Parquet is the recommended "
        "format for long logs: about a third of the CSV's size, faster to write and to read; "
        "CSV numbers read back to the same doubles); folder for many: one file per log and "
        "summary.csv",
    )
    parser.add_argument(
        "--plot", metavar="FILE", help="one log: save a figure of the estimates (.png .pdf .svg)"
    )
    parser.add_argument(
        "--smooth",
        action="store_true",
        help="offline: Rauch-Tung-Striebel smoothed loads (uses the whole log, not causal)",
    )
    parser.add_argument(
        "--still-period",
        type=float,
        metavar="SECONDS",
        help="zero the travel sensors over the first SECONDS of the log (vehicle at rest)",
    )
    parser.add_argument(
        "--still-noise",
        type=float,
        metavar="M_S2",
        help="accelerometer noise (1 sigma) for the still-period check; default: from the data",
    )
    parser.add_argument(
        "--corner-weights",
        metavar="FL,FR,RL,RR",
        help="measured corner weights [kg] (scale readings) as the static loads",
    )
    parser.add_argument(
        "--in-memory",
        action="store_true",
        help="one log: read it whole into memory (default for a CSV/Parquet log with the KF: "
        "in chunks, memory bounded by the chunk)",
    )
    add_suspension_option(parser)
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def _settings(args: argparse.Namespace, vehicle_path: Path) -> EstimateSettings:
    return EstimateSettings(
        vehicle=vehicle_path,
        method=method(args.method).name,
        channels=Path(args.channels) if args.channels else None,
        still_period=args.still_period,
        still_noise=args.still_noise,
        corner_weights=args.corner_weights,
        allow_unusual=args.allow_unusual,
        wiring_checks=not args.skip_wiring_checks,
        smooth=args.smooth,
        suspension=SuspensionModel.parse(args.suspension),
    )


def run(args: argparse.Namespace) -> int:
    if args.example:
        logs = args.log or [str(example_log_path())]
        vehicle_path = vehicle_file(args)
    else:
        if not args.log or not args.vehicle:
            raise ValueError("give a LOG and --vehicle FILE, or --example")
        logs, vehicle_path = args.log, Path(args.vehicle)
    if args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    settings = _settings(args, vehicle_path)
    paths = expand_logs(logs)
    single = len(paths) == 1 and Path(logs[0]).is_file() and len(logs) == 1
    if single:
        return _run_one(paths[0], settings, args)
    return _run_many(paths, settings, args)


def _run_one(path: Path, settings: EstimateSettings, args: argparse.Namespace) -> int:
    outputs = [Path(p) for p in (args.out, args.plot) if p]
    inputs = [path, settings.vehicle, *([settings.channels] if settings.channels else [])]
    check_outputs(outputs, inputs, force=args.force)
    if args.out:
        table_format(Path(args.out))
    if args.plot:
        check_figure_suffix(Path(args.plot))
    lean = not (args.plot or args.in_memory) and takes_lean_path(path, settings)
    if lean and _run_lean(path, settings, args):
        return 0
    from wheelload.studies.pipeline import batch  # worker processes: not for the lean path

    result = batch.estimate_log(path, settings)
    estimate, signals = result.estimate, result.signals
    if args.out:
        batch.write_table(estimate.to_pandas(), Path(args.out), replace=args.force)
    if args.plot:
        from wheelload.estimators.logs.output_files import atomic_write
        from wheelload.studies.plots.estimate import plot_estimate

        title = f"{path.name} — {result.vehicle.name}"
        with atomic_write(Path(args.plot), replace=args.force) as temporary:
            plot_estimate(estimate, signals, temporary, title=title)
    text = summary(estimate, signals, result.vehicle.name)
    _print_summary(settings, text, result.notes, result.warnings, args)
    if args.plot:
        print(f"figure written to {args.plot}")
    return 0


def _run_lean(path: Path, settings: EstimateSettings, args: argparse.Namespace) -> bool:
    """``_run_one`` on the lean whole-log path (``studies/pipeline/lean_estimate.py``).

    Memory is bounded by the chunk (plus 8 bytes a sample for the time column
    and the scored errors). False (nothing written) for a log the chunked
    reader cannot take as plain numbers: the ordinary path then reads it and
    names the problem.
    """
    result = estimate_lean(path, settings, Path(args.out) if args.out else None, force=args.force)
    if result is None:
        return False
    stream = result.stream
    header = LogHeader.of(stream, has_reference=stream.reference_present is not None)
    text = summary_text(header, result.digest, result.faults, result.vehicle.name)
    _print_summary(settings, text, result.notes, result.warnings, args)
    return True


def _print_summary(settings: EstimateSettings, text: str, notes, warnings, args) -> None:
    """The method, the log's summary, its notes and warnings, and where the estimates went."""
    print(f"method {settings.method}: {method(settings.method).description}")
    print(text)
    for line in () if quiet(args) else (*notes, *(f"warning: {w}" for w in warnings)):
        print(line)  # -q: the results only
    if args.out:
        print(f"estimates written to {args.out}")


def _run_many(paths: list[Path], settings: EstimateSettings, args: argparse.Namespace) -> int:
    from wheelload.studies.pipeline import batch

    if args.plot:
        raise ValueError("--plot is for one log; with many logs give --out FOLDER")
    folder = Path(args.out) if args.out else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    if folder is not None and folder.resolve() in {p.parent.resolve() for p in paths}:
        raise ValueError(f"{folder}: holds the input logs: write the estimates into another folder")
    table = batch.run_logs(
        paths,
        settings,
        folder,
        workers=args.workers,
        dask_address=args.dask,
        force=args.force,
        progress=show_progress(args),
    )
    columns = ["log", "samples", "mode", "mean_fz_fl", "mean_fz_rr", "min_fz", "rmse_pooled"]
    shown = table[[c for c in columns + ["error"] if c in table.columns]]
    print(shown.to_string(index=False, float_format=lambda v: f"{v:.0f}"))
    for log, messages in zip(table["log"], table.get("messages", [""] * len(table))):
        if quiet(args):  # the results only
            break
        for message in messages.split(MESSAGE_SEPARATOR) if isinstance(messages, str) else ():
            print(f"{log}: {message}")  # each log's checks and notes, named
    if folder is not None:
        batch.write_table(table, folder / batch.SUMMARY_NAME, replace=args.force)
        print(f"{len(paths)} logs: estimates and {batch.SUMMARY_NAME} written to {folder}")
    failed = int((table["error"] != "").sum()) if "error" in table.columns else 0
    if failed:
        print(f"{failed} of {len(paths)} logs failed (see the error column)")
    return 1 if failed else 0
