"""``wheelload sensor-sets LOG``: the partial sensor sets on one log with reference loads."""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.models import WHEELS
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import (
    CommandTraits,
    add_common_options,
    add_vehicle_option,
    log_of,
    vehicle_for_logs,
    vehicle_of,
)

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("sensor-sets", help=CATALOG["sensor-sets"].summary)
    parser.add_argument("log", help="log (CSV or Parquet) with all channels and reference loads")
    add_vehicle_option(parser)
    parser.add_argument(
        "--splits", type=float, nargs="+", default=[0.3, 0.4, 0.45, 0.55, 0.6, 0.7],
        help="roll_split_front values for the IMU-only sweep (the default split is added)",
    )  # fmt: skip
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.estimators.registry import build
    from wheelload.studies.experiments.sensor_sets import (
        absent_channels,
        reference_split,
        sensor_set_table,
        split_sweep,
    )
    from wheelload.studies.pipeline.log_settings import expand_logs

    (path,) = expand_logs([args.log])
    vehicle = vehicle_of(vehicle_for_logs(args, [path]), args)
    frame = log_of(path, args).to_frame()
    table = sensor_set_table(frame, vehicle, Path(path).name)
    print(f"{Path(path).name} on vehicle '{vehicle.name}'")
    for note in absent_channels(frame):
        print(f"note: {note}")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.0f}"))
    default = float(build("kf", vehicle).parameters.roll_split_front)
    missing = [f"fz_{w}" for w in WHEELS if not frame[f"fz_{w}"].notna().any()]
    if missing:  # the log's own split needs the lateral transfer of both axles
        own = f"n/a (needs reference loads on all four wheels; no {', '.join(missing)})"
        splits = sorted({*args.splits, round(default, 4)})
    else:
        truth = reference_split(frame, vehicle)
        own = f"{truth:.4f}"
        splits = sorted({*args.splits, round(default, 4), round(truth, 4)})
    print(
        f"\nroll split: default {default:.4f} (springs, bars and roll centres), the log's own {own}"
    )
    print(
        split_sweep(frame, vehicle, splits).to_string(
            index=False, float_format=lambda v: f"{v:.4g}", na_rep="n/a"
        )
    )
    return 0
