"""Options shared by several sub-commands."""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.models import example_vehicle_path


def add_allow_unusual(parser: argparse.ArgumentParser) -> None:
    """``--allow-unusual``: accept a vehicle file outside the physical ranges."""
    parser.add_argument(
        "--allow-unusual",
        action="store_true",
        help="accept a vehicle file whose values lie outside the physical ranges "
        "(models/vehicle/plausibility.py), for a special vehicle",
    )


def add_suspension_option(parser: argparse.ArgumentParser) -> None:
    """``--suspension full|paper``: the vehicle model of the family methods."""
    from wheelload.estimators import DEFAULT_MODEL, SuspensionModel

    parser.add_argument(
        "--suspension",
        choices=[m.value for m in SuspensionModel],
        default=DEFAULT_MODEL.value,
        help="vehicle model of the family methods (B-F, ycoo, umvf, road-angle, corner): "
        "full = the KF's own suspension and equilibrium model with the vehicle file's terms "
        "(default: a comparison on one model), paper = the source papers' bare spring/damper/"
        "bar model and body-axis equilibrium; kf, projection and mhe use the vehicle file's",
    )


def add_vehicle_option(parser: argparse.ArgumentParser) -> None:
    """``--vehicle FILE``, the bundled sports car by default (:func:`vehicle_file`)."""
    parser.add_argument("--vehicle", help="vehicle TOML file (default: bundled sports car)")


def vehicle_file(args: argparse.Namespace) -> Path:
    """The ``--vehicle`` file, or the bundled sports car's."""
    return Path(args.vehicle) if args.vehicle else example_vehicle_path()


def add_vehicle_file_options(parser: argparse.ArgumentParser) -> None:
    """``--vehicle FILE`` (:func:`add_vehicle_option`) and ``--allow-unusual``."""
    add_vehicle_option(parser)
    add_allow_unusual(parser)
