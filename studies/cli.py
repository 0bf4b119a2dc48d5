"""The ``wheelload`` console command: one sub-command per module.

Each module named in :data:`COMMANDS` exposes ``register(subparsers)``, which
adds its sub-parser and sets ``handler`` (a function of the parsed arguments
returning an exit status).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from importlib.metadata import version

COMMANDS = (
    "wheelload.studies.commands.vehicle",
    "wheelload.studies.commands.estimate",
    "wheelload.studies.commands.methods",
    "wheelload.studies.commands.compare",
    "wheelload.studies.commands.channels",
    "wheelload.studies.commands.sensor_sets",
    "wheelload.studies.commands.bench",
    "wheelload.studies.commands.simulate",
    "wheelload.studies.commands.mhe",
    "wheelload.studies.commands.codegen",
    "wheelload.studies.commands.weigh",
    "wheelload.studies.commands.identify",
    "wheelload.studies.commands.tune",
    "wheelload.studies.commands.identify_study",
    "wheelload.studies.commands.ablation",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wheelload",
        description="Wheel normal-load estimation from suspension travel and IMU signals.",
    )
    parser.add_argument("--version", action="version", version=version("wheelload"))
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        importlib.import_module(module).register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except (ValueError, FileNotFoundError) as error:
        print(f"wheelload {args.command}: error: {error}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a command that stopped reading (head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except OSError as error:  # e.g. a disk full or a folder made read-only while running
        where = f"{error.filename}: " if error.filename else ""
        print(
            f"wheelload {args.command}: error: {where}{error.strerror or error}: "
            "check the path, its permissions and the free space",
            file=sys.stderr,
        )
        return 2


if __name__ == "__main__":
    sys.exit(main())
