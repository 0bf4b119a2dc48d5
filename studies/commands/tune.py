"""``wheelload tune LOG ... --vehicle FILE --out NEW.toml``: fit the filter's noise densities.

Maximum likelihood of the filter's innovations (prediction-error method) for the
constant and the input-dependent densities (``models/measurement_noise.py``); the
ratios the leave-one-log-out fits do not agree on stay the input file's; with
reference loads ``fz_*`` in every log also the RMSE-minimising tuning, the blend
of input and likelihood shape no tuning log objects to, and a ±2σ coverage
calibration (``wheelload.estimators.identification.tuning``). The new file is a
copy of ``--vehicle`` with new ``[filter]`` densities and, with references,
``gate_scale = 1/c`` for densities scaled by c (the gate keeps its decisions, so
only σ is calibrated) and the reported-σ model's ``sigma_*`` fitted on the logs
(``wheelload.estimators.identification.sigma_fit``; without references the input
file's are kept). The logic is :mod:`wheelload.studies.pipeline.tuning`; this module parses,
calls it and prints."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from wheelload.models.vehicle.file import check_output_path, write_vehicle_text
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    check_logs_exist,
    log_of,
    vehicle_of,
)

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "tune",
        help=CATALOG["tune"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("logs", nargs="+", metavar="LOG", help="log files (.csv or .parquet)")
    parser.add_argument(
        "--vehicle",
        required=True,
        metavar="FILE",
        help="vehicle TOML file to start from (read only)",
    )
    parser.add_argument(
        "--out", required=True, metavar="FILE", help="file: the new vehicle file (.toml)"
    )
    parser.add_argument(
        "--evaluate",
        nargs="+",
        default=[],
        metavar="LOG",
        help="logs not used for tuning, with reference loads: print the before/after table",
    )
    parser.add_argument(
        "--iterations",
        type=int,
        default=400,
        help="Nelder-Mead iterations per fit (default 400; fewer for a quick look)",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.studies.pipeline.tuning import (
        evaluation_table,
        reference_notes,
        tune_file,
        tuned_text,
    )

    vehicle_path = Path(args.vehicle)
    inputs = (vehicle_path, *map(Path, args.logs))
    out = check_output_path(args.out, inputs, args.force)
    check_logs_exist(args.logs, "LOG")
    check_logs_exist(args.evaluate, "--evaluate")
    vehicle = vehicle_of(vehicle_path, args)
    logs = tuple(log_of(path, args) for path in args.logs)
    evaluated = tuple(log_of(path, args) for path in args.evaluate)  # read before the fit
    for path, log in zip(args.evaluate, evaluated):
        if not log.reference_present.any():
            raise ValueError(
                f"{path}: no reference loads fz_fl..fz_rr; --evaluate needs logs with them"
            )
    for note in reference_notes(logs + evaluated):
        print(f"note: {note}", file=sys.stderr)
    tuned = tune_file(vehicle, logs, iterations=args.iterations)
    print("\n".join(tuned.report))
    for warning in tuned.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    write_vehicle_text(
        tuned_text(vehicle_path.read_text(encoding="utf-8"), tuned, vehicle_path.name),
        out,
        inputs=inputs,
        force=args.force,
        allow_unusual=args.allow_unusual,
    )
    print(f"vehicle file written to {out}")
    if evaluated:
        table, warnings = evaluation_table(vehicle, tuned.vehicle, evaluated)
        for warning in warnings:
            print(f"warning: {warning}", file=sys.stderr)
        print(table)
    return 0
