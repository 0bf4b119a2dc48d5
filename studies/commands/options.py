"""Options shared by several sub-commands."""

from __future__ import annotations

import argparse
import logging
import sys
from dataclasses import dataclass
from pathlib import Path

logger = logging.getLogger(__name__)


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
        "bar model and body-axis equilibrium; kf, projection and mhe keep theirs (the "
        "vehicle file's; wheelload study --model chooses it)",
    )


def add_vehicle_option(parser: argparse.ArgumentParser) -> None:
    """``--vehicle FILE``, the bundled sports car by default (:func:`vehicle_file`)."""
    parser.add_argument("--vehicle", help="vehicle TOML file (default: bundled sports car)")


def vehicle_file(args: argparse.Namespace) -> Path:
    """The ``--vehicle`` file, or the bundled sports car's."""
    from wheelload.models import example_vehicle_path  # casadi: not for --version

    return Path(args.vehicle) if args.vehicle else example_vehicle_path()


def add_vehicle_file_options(parser: argparse.ArgumentParser) -> None:
    """``--vehicle FILE`` (:func:`add_vehicle_option`) and ``--allow-unusual``."""
    add_vehicle_option(parser)
    add_allow_unusual(parser)


@dataclass(frozen=True, kw_only=True)
class CommandTraits:
    """What a command reads and writes: the shared option groups it takes.

    ``log``: reads logs (``--channels``, ``--skip-wiring-checks``); ``scores``: scores
    against reference loads in a window (``--start``, ``--end``); ``vehicle``: reads a
    vehicle file (``--allow-unusual``); ``writes``: writes files (``--force``);
    ``many_logs``: runs many logs or jobs (``--workers``, ``--dask``, ``--no-progress``).
    Every command takes ``-q``/``-v`` (:func:`add_message_options`).
    """

    log: bool = False
    scores: bool = False
    vehicle: bool = False
    writes: bool = False
    many_logs: bool = False
    workers: int = 1  # the default of --workers


#: Titles of the option groups (``wheelload COMMAND --help`` shows them as sections).
GROUPS = {
    "log": "log input",
    "scores": "scoring window",
    "vehicle": "vehicle file",
    "writes": "output",
    "many_logs": "many logs",
    "messages": "messages",
}


def add_common_options(parser: argparse.ArgumentParser, traits: CommandTraits) -> None:
    """The shared option groups of a command with these ``traits`` (one set for all); the
    parser keeps the declaration as its ``traits`` default."""
    parser.set_defaults(traits=traits)
    if traits.log:
        group = parser.add_argument_group(GROUPS["log"])
        group.add_argument(
            "--channels", metavar="MAP", help="channel map TOML (wheelload channels --template)"
        )
        group.add_argument(
            "--skip-wiring-checks",
            action="store_true",
            help="accept a log whose signs, units or wiring look wrong",
        )
    if traits.scores:
        group = parser.add_argument_group(GROUPS["scores"])
        group.add_argument("--start", type=float, help="score from this time [s] (default: start)")
        group.add_argument("--end", type=float, help="score up to this time [s] (default: end)")
    if traits.vehicle:
        add_allow_unusual(parser.add_argument_group(GROUPS["vehicle"]))
    if traits.writes:
        parser.add_argument_group(GROUPS["writes"]).add_argument(
            "--force", action="store_true", help="replace existing output files (never an input)"
        )
    if traits.many_logs:
        group = parser.add_argument_group(GROUPS["many_logs"])
        group.add_argument(
            "--workers",
            type=int,
            default=traits.workers,
            help=f"local processes (default {traits.workers})",
        )
        group.add_argument("--dask", metavar="ADDRESS", help="run on this Dask scheduler")
        group.add_argument(
            "--no-progress",
            action="store_true",
            help="no progress bar (default: one on a terminal)",
        )
    add_message_options(parser)


def add_message_options(parser: argparse.ArgumentParser) -> None:
    """``-q`` (errors only) and ``-v`` (``-vv``: debug), through :mod:`logging`."""
    group = parser.add_argument_group(GROUPS["messages"])
    group.add_argument(
        "-q", "--quiet", action="store_true", default=None, help="only errors on stderr"
    )
    group.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=None,
        help="more on stderr: -v what is read and done, -vv debug",
    )


def log_level(args: argparse.Namespace) -> int:
    """The :mod:`logging` level of ``-q`` / ``-v`` (default: warnings)."""
    if getattr(args, "quiet", None) or getattr(args, "quiet_top", None):
        return logging.ERROR
    verbose = (getattr(args, "verbose", None) or 0) + (getattr(args, "verbose_top", None) or 0)
    return {0: logging.WARNING, 1: logging.INFO}.get(verbose, logging.DEBUG)


def show_progress(args: argparse.Namespace) -> bool:
    """A progress bar unless ``--no-progress``, and only on a terminal."""
    return not getattr(args, "no_progress", False) and sys.stderr.isatty()


def vehicle_of(path: str | Path, args: argparse.Namespace):
    """The vehicle file at ``path`` with the command's ``--allow-unusual``."""
    from wheelload.models import load_vehicle

    return load_vehicle(Path(path), allow_unusual=getattr(args, "allow_unusual", False))


def log_of(path: str | Path, args: argparse.Namespace):
    """The log at ``path`` through the command's ``--channels`` and wiring checks."""
    from wheelload.estimators import read_log

    signals = read_log(
        path,
        channels=getattr(args, "channels", None),
        wiring_checks=not getattr(args, "skip_wiring_checks", False),
    )
    logger.info("read %s: %d samples", path, len(signals))
    return signals
