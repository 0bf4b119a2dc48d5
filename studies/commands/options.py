"""Options shared by several sub-commands."""

from __future__ import annotations

import argparse


def add_allow_unusual(parser: argparse.ArgumentParser) -> None:
    """``--allow-unusual``: accept a vehicle file outside the physical ranges."""
    parser.add_argument(
        "--allow-unusual",
        action="store_true",
        help="accept a vehicle file whose values lie outside the physical ranges "
        "(models/plausibility.py), for a special vehicle",
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
