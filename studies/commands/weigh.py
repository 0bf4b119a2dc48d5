"""``wheelload weigh LOG... --vehicle FILE [--out NEW.toml]``: mass and CG from logs at rest.

Solves the standstill balance (ycoo-umvf paper §5) for the whole-vehicle
mass, CG distance to the front axle, lateral CG offset and CG height, with
their 1-sigma uncertainties; ``--out`` writes a copy of the vehicle file with
the sprung mass, total mass, lf, lr and CG height replaced (the vehicle file
has no lateral CG offset: it is printed only).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.estimators import WeighSettings, sprung_geometry, weigh
from wheelload.models import vehicle_mass_centre
from wheelload.models.vehicle.file import (
    check_output_path,
    edited_vehicle_text,
    write_vehicle_text,
)
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options, log_of, vehicle_of

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "weigh",
        help=CATALOG["weigh"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("logs", nargs="+", metavar="LOG", help="logs at rest (.csv or .parquet)")
    parser.add_argument("--vehicle", required=True, help="vehicle TOML file (suspension, geometry)")
    parser.add_argument(
        "--out", metavar="FILE", help="file: write an updated copy of the vehicle file here"
    )
    parser.add_argument(
        "--max-speed", type=float, default=0.3, help="speed below which a sample is at rest [m/s]"
    )
    parser.add_argument(
        "--settle", type=float, default=1.0, help="seconds dropped at the start of a still period"
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    vehicle_path = Path(args.vehicle)
    vehicle = vehicle_of(vehicle_path, args)
    inputs = (vehicle_path, *(Path(p) for p in args.logs))
    if args.out:  # before the work: an output that would replace a file is refused at once
        check_output_path(args.out, inputs, args.force)
    settings = WeighSettings(max_speed=args.max_speed, settle=args.settle)
    result = weigh([log_of(path, args) for path in args.logs], vehicle, settings)
    centre = vehicle_mass_centre(vehicle)
    file_values = (vehicle.mass.total, centre.lf, 0.0, centre.height)
    print(f"{'':>22}{'estimate':>12}{'1 sigma':>10}{'file':>10}")
    labels = ("mass [kg]", "CG to front axle [m]", "CG lateral, left [m]", "CG height [m]")
    for label, value, std, file_value in zip(labels, result.values, result.std, file_values):
        print(f"{label:>22}{value:12.4f}{std:10.4f}{file_value:10.4f}")
    for attitude in result.attitudes:
        ax, ay, az = attitude.acc
        print(
            f"{attitude.source}: {attitude.samples} samples at rest, "
            f"a = ({ax:.3f}, {ay:.3f}, {az:.3f}) m/s^2"
        )
    print(f"fit: chi2 = {result.chi2:.3g} on {result.dof} degrees of freedom (whole vehicle)")
    if args.out:
        sprung = sprung_geometry(vehicle, result)
        changes = {
            ("mass", "total"): sprung["total"],
            ("mass", "sprung"): sprung["sprung"],
            ("geometry", "lf"): sprung["lf"],
            ("geometry", "lr"): sprung["lr"],
            ("geometry", "cg_height"): sprung["cg_height"],
        }
        text = edited_vehicle_text(vehicle_path.read_text(encoding="utf-8"), changes)
        write_vehicle_text(
            text, args.out, inputs=inputs, force=args.force, allow_unusual=args.allow_unusual
        )
        print(f"vehicle file written to {args.out} (sprung CG: lf {sprung['lf']:.4f} m, "
              f"height {sprung['cg_height']:.4f} m)")  # fmt: skip
    return 0
