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
