"""``wheelload vehicle``: print the commented template or check a vehicle file."""

from __future__ import annotations

import argparse

from wheelload.models import load_vehicle, static_loads, vehicle_mass_centre, vehicle_template
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(vehicle=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("vehicle", help=CATALOG["vehicle"].summary)
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--template", action="store_true", help="print a commented template")
    group.add_argument(
        "file", nargs="?", metavar="FILE", help="vehicle TOML file to check and summarise"
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.template:
        print(vehicle_template(), end="")
        return 0
    from wheelload.studies.pipeline.run_messages import (
        log_vehicle,
        log_vehicle_ranges,
        log_vehicle_terms,
        phase,
    )

    with phase(f"read and check {args.file}"):
        vehicle = load_vehicle(args.file, allow_unusual=args.allow_unusual)
    log_vehicle(args.file, vehicle)
    log_vehicle_terms(vehicle)
    log_vehicle_ranges(vehicle)
    centre = vehicle_mass_centre(vehicle)
    loads = static_loads(vehicle)
    print(f"{args.file}: valid vehicle '{vehicle.name}'")
    print(
        f"  total mass {vehicle.mass.total:.1f} kg, whole-vehicle CG: lf {centre.lf:.3f} m, "
        f"lr {centre.lr:.3f} m, height {centre.height:.3f} m"
    )
    print(
        "  static loads [N]: "
        + ", ".join(f"{w} {f:.0f}" for w, f in zip(("FL", "FR", "RL", "RR"), loads))
    )
    return 0
