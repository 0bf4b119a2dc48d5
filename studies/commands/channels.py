"""``wheelload channels``: write, list and check channel maps (estimators/logs/readers).

``--template`` prints a commented map; ``--list LOG`` the channels of a log
(any format); ``MAP`` checks a map, and with ``--log LOG`` reads the log
through it and prints what came out (rate, sensor set, ranges in SI units).
"""

from __future__ import annotations

import argparse

import numpy as np

from wheelload.estimators import read_log
from wheelload.estimators.logs.readers import channel_map_template, channel_names, load_channel_map
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits()


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("channels", help=CATALOG["channels"].summary)
    parser.add_argument("map", nargs="?", help="channel map TOML file to check")
    parser.add_argument(
        "--template", action="store_true", help="print a commented channel-map template"
    )
    parser.add_argument("--list", metavar="LOG", help="print the channel names of LOG")
    parser.add_argument("--log", help="read this log through MAP and summarise it")
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.template:
        print(channel_map_template(), end="")
        return 0
    if args.list:
        print("\n".join(channel_names(args.list)))
        return 0
    if not args.map:
        raise ValueError("give --template, --list LOG, or a channel map FILE (with --log LOG)")
    channel_map = load_channel_map(args.map)
    for name, spec in channel_map.channels.items():
        extras = [f"sign {spec.sign:+.0f}"]
        if spec.motion_ratio != 1.0:
            extras.append(f"motion ratio {spec.motion_ratio:g}")
        if spec.radius is not None:
            extras.append(f"radius {spec.radius:g} m, ratio {spec.ratio:g}")
        method = (spec.method or channel_map.clock.method).value
        unit = spec.unit or "the log's unit"
        print(f"{name:>6} <- {spec.source} [{unit}] {', '.join(extras)}, {method}")
    print(f"clock: {channel_map.clock.channel}, gaps > {channel_map.clock.max_gap:g} s missing")
    if args.log:
        signals = read_log(args.log, channels=args.map)
        print(f"{args.log}: {len(signals)} samples at {signals.sample_rate:.1f} Hz; "
              f"{signals.mode()}")  # fmt: skip
        frame = signals.to_frame()
        for column in frame.columns:
            values = frame[column].to_numpy()
            finite = values[np.isfinite(values)]
            if finite.size:
                print(f"{column:>6} {finite.min():12.5g} .. {finite.max():<12.5g} "
                      f"missing {values.size - finite.size}")  # fmt: skip
            else:
                print(f"{column:>6} no sample")
    return 0
