"""``wheelload simulate NAME --out LOG``: run a scenario on the ground-truth plant.

The wall time of every scenario is printed by ``wheelload bench scenarios``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.estimators.logs.output_files import check_figure_suffix, check_outputs, table_format
from wheelload.models.payload import Payload
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    add_vehicle_option,
    vehicle_file,
    vehicle_of,
)
from wheelload.studies.drive.can_car import CanCar, can_outputs, write_can_logs
from wheelload.studies.drive.payload_schedule import PayloadChange, PayloadSchedule
from wheelload.studies.drive.rig import RigSettings, rig_sweep, write_rig
from wheelload.studies.drive.roads import ISO_CLASSES
from wheelload.studies.drive.scenario_log import metadata_path, write_log
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.scenarios import SCENARIOS
from wheelload.studies.drive.sensors import GRADES, MTI_1, sensor_grade
from wheelload.studies.plots.scenario import plot_scenario

RIG_SWEEP = "rig-sweep"


#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help=CATALOG["simulate"].summary,
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
        metavar="FILE",
        help=f"file: the log (.csv or .parquet); for {RIG_SWEEP} the corner-rig CSV (the bar-rig "
        "file is written beside it as <stem>_arb.csv)",
    )
    parser.add_argument("--plot", help="save a figure (.png, .pdf, .svg) of the run")
    add_vehicle_option(parser)
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
    parser.add_argument("--rate", type=float, default=100.0, help="output rate [Hz] (default 100)")
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
    parser.add_argument(
        "--payload",
        metavar="KG[,X,Y,Z]",
        help="the plant carries a point mass KG [kg] at X,Y,Z [m] from the vehicle file's "
        "sprung CG (x forward, y left, z up; default 0,0,0); the file does not know it",
    )
    parser.add_argument(
        "--payload-change",
        metavar="T,KG[,X,Y,Z]",
        help="the payload becomes KG at X,Y,Z from time T [s] on, over 1.5 s, while the car "
        "stands still (standstill, stop-and-go)",
    )
    parser.add_argument(
        "--can",
        metavar="DIR",
        help="also write the log as the CAN car of studies/data/can_car.dbc sends it: "
        "DIR/STEM.mf4 (bus logging), DIR/STEM.blf, the DBC and two channel maps",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def parse_payload(text: str, option: str = "--payload") -> Payload:
    """``KG[,X,Y,Z]`` as a :class:`Payload`, or a one-line error naming ``option``."""
    form = f"{option} expects KG[,X,Y,Z] (kg, then m from the sprung CG), e.g. 150,0.3,0.4,0.1"
    parts = text.split(",")
    try:
        numbers = [float(part) for part in parts]
    except ValueError:
        raise ValueError(f"{option} '{text}': not numbers; {form}") from None
    if len(numbers) not in (1, 4):
        raise ValueError(f"{option} '{text}': {len(numbers)} values; {form}")
    mass, x, y, z = numbers if len(numbers) == 4 else (numbers[0], 0.0, 0.0, 0.0)
    try:
        return Payload(mass=mass, x=x, y=y, z=z)
    except ValueError as error:
        raise ValueError(f"{option} '{text}': {error}") from None


def parse_payload_change(text: str) -> PayloadChange:
    """``T,KG[,X,Y,Z]`` as a :class:`PayloadChange`, or a one-line error."""
    option = "--payload-change"
    time, _, rest = text.partition(",")
    form = f"{option} expects T,KG[,X,Y,Z] (s, kg, m), e.g. 5,80,0.2,-0.4,0.1"
    try:
        at = float(time)
    except ValueError:
        raise ValueError(f"{option} '{text}': time '{time}' is not a number; {form}") from None
    if not rest:
        raise ValueError(f"{option} '{text}': no payload after the time; {form}")
    payload = parse_payload(rest, option)
    try:
        return PayloadChange(time=at, payload=payload)
    except ValueError as error:
        raise ValueError(f"{option} '{text}': {error}") from None


def payload_schedule(args: argparse.Namespace) -> PayloadSchedule | None:
    """The payload options as a schedule, or None without them."""
    if args.payload is None and args.payload_change is None:
        return None
    initial = Payload(mass=0.0) if args.payload is None else parse_payload(args.payload)
    change = None if args.payload_change is None else parse_payload_change(args.payload_change)
    return PayloadSchedule(initial=initial, change=change)


def handle(args: argparse.Namespace) -> int:
    vehicle = vehicle_file(args)
    if args.name == RIG_SWEEP:
        return _rig(args, vehicle)
    payload = payload_schedule(args)
    out = Path(args.out)
    outputs = [out, metadata_path(out), *([Path(args.plot)] if args.plot else [])]
    outputs += can_outputs(Path(args.can), out.stem) if args.can else []
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
        payload=payload,
        sensors=sensor_grade(args.sensors),
    )
    sidecar = write_log(result.log, out, result.metadata, replace=args.force)
    if args.can:
        tyres = vehicle_of(vehicle, args).tyres
        car = CanCar(wheel_radius=(tyres.radius_front, tyres.radius_rear))
        can_files = write_can_logs(result.log, Path(args.can), out.stem, car, replace=args.force)
        print(f"CAN car logs: {', '.join(str(path) for path in can_files)}")
    if args.plot:
        title = f"{args.name} ({result.metadata['vehicle']})"
        plot_scenario(result.truth.frame, args.plot, title, replace=args.force)
    info = result.metadata["summary"]
    print(
        f"{args.name} on vehicle '{result.metadata['vehicle']}': {len(result.log)} samples, "
        f"{info['duration_s']:.1f} s simulated in "
        f"{result.truth.wall_time:.2f} s (+{result.truth.build_time:.1f} s build); "
        f"log {args.out}, metadata {sidecar}"
    )
    return 0


def _rig(args: argparse.Namespace, vehicle) -> int:
    if (
        args.noise != 1.0
        or args.roughness
        or args.plot
        or args.sensors != MTI_1.name
        or args.payload
        or args.payload_change
    ):
        raise ValueError(
            f"--noise, --sensors, --roughness, --plot and the payload options do not apply to "
            f"{RIG_SWEEP}"
        )
    settings = RigSettings(seed=args.seed, rate=args.rate)
    corner, bar = rig_sweep(vehicle_of(vehicle, args), settings)
    paths = write_rig(corner, bar, args.out, force=args.force)
    print(
        f"{RIG_SWEEP}: {len(corner)} corner-rig and {len(bar)} bar-rig samples "
        f"({settings.duration:.0f} s per corner and axle at {settings.rate:.0f} Hz); "
        f"files {paths[0]}, {paths[1]}"
    )
    return 0
