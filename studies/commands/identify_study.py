"""``wheelload identify-study``: a wrong vehicle file put right by identify and tune, on the plant.

Prints two tables (``studies/experiments/identification_study.py``): the two-stage KF's
pooled RMSE with the true, the wrong (springs -20 %, dampers +30 %, bars
-30 %) and the identified file on scenarios not used for identification;
and ±2σ coverage and RMSE of the input and the tuned filter on logs not used
for tuning. ``--quick`` uses three scenarios.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options, vehicle_of
from wheelload.studies.drive.scenario_names import SCENARIO_NAMES
from wheelload.studies.experiments.runs.choices import IDENTIFY_ON

QUICK = ("accel-in-turn", "iso-dlc", "slope-20")  # identified from accel-in-turn


#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "identify-study",
        help=CATALOG["identify-study"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument(
        "--out",
        default="identify-study",
        metavar="DIR",
        help="folder for logs and tables (default identify-study)",
    )
    parser.add_argument("--quick", action="store_true", help="three scenarios only")
    parser.add_argument(
        "--identify-on",
        choices=sorted(SCENARIO_NAMES),
        help=f"the one drive log to identify from (default {IDENTIFY_ON}; --quick: {QUICK[0]})",
    )
    parser.add_argument(
        "--vehicle", help="the true vehicle file the plant runs (default: the bundled sports car)"
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    from wheelload.studies.experiments.identification_study import StudySettings, run_study

    settings = StudySettings()
    if args.quick:
        settings = StudySettings(scenarios=QUICK, identify_on=QUICK[0])
    if args.identify_on:
        settings = dataclasses.replace(settings, identify_on=args.identify_on)
    if args.vehicle:
        path = Path(args.vehicle)
        vehicle_of(path, args)  # a one-line error for a bad file before any simulation
        settings = dataclasses.replace(settings, vehicle=path)
    folder = Path(args.out)
    tables = [folder / f"{name}.csv" for name in ("identification", "tuning")]
    existing = [path for path in tables if path.exists()]
    if existing and not args.force:
        raise ValueError(f"{existing[0]} exists: choose another --out or add --force")
    identification, tuning = run_study(settings, folder)
    for name, frame in (("identification", identification), ("tuning", tuning)):
        target = folder / f"{name}.csv"
        frame.to_csv(target, index=False, float_format="%.6g")
    print(
        f"KF pooled RMSE [N], {settings.vehicle.name}; file identified from "
        f"{settings.identify_on} "
        f"(start: springs x{settings.spring}, dampers x{settings.damper}, bars x{settings.bar})"
    )
    print(identification.to_string(index=False, float_format="%.1f"))
    print(
        f"\ntuned on {', '.join(settings.tune_on)}: [q, r_s, r_c, r_sv, r_sh, r_ca] ="
        f" {tuning.attrs['tuned']}"
    )
    print(tuning.to_string(index=False, float_format="%.1f"))
    print(f"tables written to {folder}")
    return 0
