"""``wheelload simulate NAME --out LOG``: run a scenario on the ground-truth plant.

The wall time of every scenario is printed by ``wheelload bench scenarios``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.estimators.logs.output_files import check_figure_suffix, check_outputs, table_format
from wheelload.models.vehicle.file import example_vehicle_path, load_vehicle
from wheelload.studies.commands.options import add_allow_unusual
from wheelload.studies.drive.rig import RigSettings, rig_sweep, write_rig
from wheelload.studies.drive.roads import ISO_CLASSES
from wheelload.studies.drive.scenario_log import metadata_path, write_log
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.scenarios import SCENARIOS
from wheelload.studies.drive.sensors import GRADES, MTI_1, sensor_grade
from wheelload.studies.plots.scenario import plot_scenario

RIG_SWEEP = "rig-sweep"


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help="simulate a scenario and write a log with reference loads",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument(
        "name",
        choices=[*sorted(SCENARIOS), RIG_SWEEP],
        metavar="NAME",
        help="scenario: "
        + ", ".join(sorted(SCENARIOS))
        + f"; or {RIG_SWEEP}: component-rig sweeps of the plant's suspension force elements",
    )
    parser.add_argument(
        "--out",
        required=True,
        help=f"log file (.csv or .parquet); for {RIG_SWEEP} the corner-rig CSV (the bar-rig "
        "file is written beside it as <stem>_arb.csv)",
    )
    parser.add_argument("--plot", help="save a figure (.png, .pdf, .svg) of the run")
    parser.add_argument(
        "--force", action="store_true", help="replace existing output files (never an input)"
    )
    parser.add_argument("--vehicle", default=None, help="vehicle file (default: bundled)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (noise, roughness)")
    parser.add_argument(
        "--noise", type=float, default=1.0, help="sensor noise scale s (0 = clean signals)"
    )
    parser.add_argument(
        "--sensors",
        choices=list(GRADES),
        default=MTI_1.name,
        help=f"sensor grade (default {MTI_1.name}; clean: noise-free)",
    )
    parser.add_argument("--rate", type=float, default=100.0, help="output rate [Hz]")
    parser.add_argument(
        "--internal-rate",
        type=float,
        default=1000.0,
        help="plant integration rate [Hz], a multiple of --rate",
    )
    parser.add_argument(
        "--roughness",
        choices=ISO_CLASSES,
        default=None,
        help="ISO 8608 road class (default: smooth road)",
    )
    parser.add_argument(
        "--grade",
        type=float,
        default=0.0,
        help="standstill: road grade, rise over run (0.2 = 20 %%)",
    )
    parser.add_argument(
        "--bank", type=float, default=0.0, help="standstill: road bank, rise over run, left up > 0"
    )
    add_allow_unusual(parser)
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    vehicle = args.vehicle or example_vehicle_path()
    if args.name == RIG_SWEEP:
        return _rig(args, vehicle)
    out = Path(args.out)
    outputs = [out, metadata_path(out), *([Path(args.plot)] if args.plot else [])]
    check_outputs(outputs, [Path(vehicle)], force=args.force)
    table_format(out)
    if args.plot:
        check_figure_suffix(Path(args.plot))
    if (args.grade or args.bank) and args.name != "standstill":
        raise ValueError("--grade and --bank apply to the standstill scenario only")
    options = Options(roughness=args.roughness, seed=args.seed, grade=args.grade, bank=args.bank)
    result = run_scenario(
        args.name,
        vehicle,
        options=options,
        noise=args.noise,
        output_rate=args.rate,
        internal_rate=args.internal_rate,
        allow_unusual=args.allow_unusual,
        sensors=sensor_grade(args.sensors),
    )
    sidecar = write_log(result.log, out, result.metadata, replace=args.force)
    if args.plot:
        title = f"{args.name} ({result.metadata['vehicle']})"
        plot_scenario(result.truth.frame, args.plot, title, replace=args.force)
    info = result.metadata["summary"]
    print(
        f"{args.name}: {len(result.log)} samples, {info['duration_s']:.1f} s simulated in "
        f"{result.truth.wall_time:.2f} s (+{result.truth.build_time:.1f} s build); "
        f"log {args.out}, metadata {sidecar}"
    )
    return 0


def _rig(args: argparse.Namespace, vehicle) -> int:
    if args.noise != 1.0 or args.roughness or args.plot or args.sensors != MTI_1.name:
        raise ValueError(f"--noise, --sensors, --roughness and --plot do not apply to {RIG_SWEEP}")
    settings = RigSettings(seed=args.seed, rate=args.rate)
    corner, bar = rig_sweep(load_vehicle(vehicle), settings)
    paths = write_rig(corner, bar, args.out, force=args.force)
    print(
        f"{RIG_SWEEP}: {len(corner)} corner-rig and {len(bar)} bar-rig samples "
        f"({settings.duration:.0f} s per corner and axle at {settings.rate:.0f} Hz); "
        f"files {paths[0]}, {paths[1]}"
    )
    return 0
