"""``wheelload identify``: fit the suspension maps of a vehicle file to rig data and drive logs.

Writes a new vehicle file (a copy of ``--vehicle`` with the identified values,
each with its standard error and data source in a comment) and, with
``--report DIR``, a Markdown report, CSV tables and figures. Rig and log
formats: ``wheelload.estimators.identification.data``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.models.vehicle.file import (
    check_output_path,
    write_text_atomically,
    write_vehicle_text,
)
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options, vehicle_of

REPORT_FILES = (
    "report.md",
    "parameters.csv",
    "rmse.csv",
    "correlation.csv",
    "maps.png",
    "residuals.png",
)


#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "identify",
        help=CATALOG["identify"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("--vehicle", required=True, help="vehicle file to start from (read only)")
    parser.add_argument(
        "--out", required=True, metavar="FILE", help="file: the new vehicle file (.toml)"
    )
    parser.add_argument("--report", metavar="DIR", help="write report.md, CSV tables and figures")
    parser.add_argument("--rig", action="append", default=[], metavar="CSV", help="rig file")
    parser.add_argument(
        "--drive", action="append", default=[], metavar="LOG", help="drive log with fz_* columns"
    )
    parser.add_argument(
        "--robust", choices=("huber", "soft-l1"), help="robust loss instead of least squares"
    )
    parser.add_argument(
        "--damper",
        choices=("linear", "piecewise"),
        default="linear",
        help="damper map: linear (default) or piecewise linear in the velocity (--knots)",
    )
    parser.add_argument(
        "--knots", help="inner velocity knots of the piecewise damper [m/s], e.g. 0.1,0.3"
    )
    parser.add_argument(
        "--instrumental",
        action="store_true",
        help="two-stage least squares with instruments (the drive logs' samples two steps "
        "before and after) against sensor noise in travel rates and accelerations",
    )
    parser.add_argument("--fix", default="", help="parameters held at the file value, NAME,...")
    parser.add_argument(
        "--max-relative-std",
        dest="precision",
        metavar="RATIO",
        type=float,
        default=0.25,
        help="hold a parameter whose 1σ relative precision is worse than this (default 0.25)",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def _knots(args: argparse.Namespace) -> tuple[float, ...]:
    if args.damper == "linear":
        if args.knots:
            raise ValueError("--knots needs --damper piecewise")
        return ()
    if not args.knots:
        raise ValueError("--damper piecewise needs --knots V1,V2,... (m/s)")
    try:
        return tuple(float(k) for k in args.knots.split(","))
    except ValueError:
        raise ValueError(f"--knots '{args.knots}': give numbers in m/s, e.g. 0.1,0.3") from None


def handle(args: argparse.Namespace) -> int:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.estimators.identification import FitLoss
    from wheelload.estimators.identification.report import parameter_table
    from wheelload.studies.pipeline.identification import identify_vehicle

    vehicle_path = Path(args.vehicle)
    vehicle_of(vehicle_path, args)  # the vehicle file's errors before the outputs'
    inputs = (vehicle_path, *map(Path, args.rig), *map(Path, args.drive))
    out = check_output_path(args.out, inputs, args.force)
    report = Path(args.report) if args.report else None
    if report is not None and not args.force:
        existing = [name for name in REPORT_FILES if (report / name).exists()]
        if existing:
            raise ValueError(f"{report / existing[0]} exists: choose another --report or --force")
    identified = identify_vehicle(
        vehicle_path,
        rig=args.rig,
        drive=args.drive,
        knots=_knots(args),
        loss=FitLoss(args.robust) if args.robust else FitLoss.LINEAR,
        fixed=frozenset(name.strip() for name in args.fix.split(",") if name.strip()),
        precision=args.precision,
        instrumental=args.instrumental,
        allow_unusual=args.allow_unusual,
        channel_map=args.channels,
        wiring_checks=not args.skip_wiring_checks,
    )
    result, keys = identified.result, identified.keys
    write_vehicle_text(
        identified.text, out, inputs=inputs, force=args.force, allow_unusual=args.allow_unusual
    )
    params = parameter_table(result, keys)
    print(f"identified {len(result.free)} parameters from {len(identified.sets)} data sets:")
    print(params.drop(columns=["sources"]).to_string(index=False, float_format="%.5g"))
    for warning in result.warnings:
        print(f"warning: {warning}")
    print(f"vehicle file written to {out}")
    if report is not None:
        _write_report(result, keys, report, vehicle_path, out)
    return 0


def _write_report(result, keys, report: Path, vehicle_path: Path, out: Path) -> None:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.estimators.identification.report import (
        correlation_table,
        markdown_report,
        parameter_table,
        rmse_table,
    )
    from wheelload.studies.plots.identification import plot_maps, plot_residuals

    report.mkdir(parents=True, exist_ok=True)
    tables = {
        "parameters.csv": parameter_table(result, keys),
        "rmse.csv": rmse_table(result),
        "correlation.csv": correlation_table(result),
    }
    for name, frame in tables.items():
        write_text_atomically(
            frame.to_csv(index=name == "correlation.csv", float_format="%.9g"), report / name
        )
    figures = [plot_maps(result, report / "maps.png")]
    residuals = plot_residuals(result, report / "residuals.png")
    if residuals is not None:
        figures.append(residuals)
    text = markdown_report(
        result,
        keys,
        vehicle=str(vehicle_path),
        output=str(out),
        figures=tuple(str(f) for f in figures),
    )
    write_text_atomically(text, report / "report.md")
    print(f"report written to {report / 'report.md'}")
