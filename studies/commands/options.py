"""Options shared by several sub-commands."""

from __future__ import annotations

import argparse
import logging
import sys
from dataclasses import dataclass
from pathlib import Path


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
    parser.add_argument(
        "--vehicle",
        metavar="FILE",
        help="vehicle TOML file (default: the bundled sports car, named on stderr; "
        "required with a log of yours)",
    )


def vehicle_file(args: argparse.Namespace) -> Path:
    """The ``--vehicle`` file, or the bundled sports car's, named on stderr (:func:`tell`)."""
    from wheelload.models import example_vehicle_path  # casadi: not for --version
    from wheelload.studies.pipeline.vehicle_choice import bundled_line

    if args.vehicle:
        return Path(args.vehicle)
    tell(args, bundled_line(args.command))
    return example_vehicle_path()


def vehicle_for_logs(args: argparse.Namespace, logs) -> Path:
    """The ``--vehicle`` file; without it the bundled car's for logs recorded on it (named on
    stderr), a one-line error for a log of the user's
    (:func:`~wheelload.studies.pipeline.vehicle_choice.vehicle_for_logs`)."""
    from wheelload.studies.pipeline import vehicle_choice

    path = vehicle_choice.vehicle_for_logs(args.vehicle, logs, args.command)
    if not args.vehicle:
        tell(args, vehicle_choice.bundled_line(args.command))
    return path


def quiet(args: argparse.Namespace) -> bool:
    """``-q``: only results and errors."""
    return bool(getattr(args, "quiet", None) or getattr(args, "quiet_top", None))


def tell(args: argparse.Namespace, line: str) -> None:
    """A line for the user on stderr (not a result), unless ``-q``; held until the
    arguments are checked (:func:`told`), so that a mistake stays one line."""
    if not quiet(args):
        vars(args).setdefault("untold", []).append(line)


def told(args: argparse.Namespace) -> None:
    """Print the lines :func:`tell` holds: the arguments are checked, the work starts (the
    console command calls it too when the command has run)."""
    for line in vars(args).pop("untold", []):
        print(line, file=sys.stderr)


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


#: ``--workers``' default on every command: one local process (the command's own).
WORKERS = 1


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
            default=WORKERS,
            metavar="N",
            help=f"local processes (default {WORKERS}: this one; more run logs or jobs in "
            "parallel)",
        )
        group.add_argument("--dask", metavar="ADDRESS", help="run on this Dask scheduler")
        group.add_argument(
            "--no-progress",
            action="store_true",
            help="no progress bar (default: one on a terminal)",
        )
    add_message_options(parser)


def add_message_options(parser: argparse.ArgumentParser) -> None:
    """``-q`` (the results and errors only) and ``-v`` (``-vv``: each check's numbers),
    through :mod:`logging` (:mod:`~wheelload.studies.pipeline.run_messages`)."""
    group = parser.add_argument_group(GROUPS["messages"])
    group.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=None,
        help="only the results and errors (no notes, warnings or bundled-car line)",
    )
    group.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=None,
        help="more on stderr: -v what is read, derived and done with timings per phase, "
        "-vv each check's numbers",
    )


def log_level(args: argparse.Namespace) -> int:
    """The :mod:`logging` level of ``-q`` / ``-v`` (default: warnings)."""
    if quiet(args):
        return logging.ERROR
    verbose = (getattr(args, "verbose", None) or 0) + (getattr(args, "verbose_top", None) or 0)
    return {0: logging.WARNING, 1: logging.INFO}.get(verbose, logging.DEBUG)


def show_progress(args: argparse.Namespace) -> bool:
    """A progress bar unless ``--no-progress``, and only on a terminal."""
    return not getattr(args, "no_progress", False) and sys.stderr.isatty()


def vehicle_of(path: str | Path, args: argparse.Namespace):
    """The vehicle file at ``path`` with the command's ``--allow-unusual``."""
    from wheelload.models import load_vehicle
    from wheelload.studies.pipeline.run_messages import log_vehicle

    vehicle = load_vehicle(Path(path), allow_unusual=getattr(args, "allow_unusual", False))
    log_vehicle(path, vehicle)
    return vehicle


def log_of(path: str | Path, args: argparse.Namespace):
    """The log at ``path`` through the command's ``--channels`` and wiring checks."""
    from wheelload.estimators import read_log
    from wheelload.studies.pipeline.run_messages import log_signals, phase

    channels, skip = getattr(args, "channels", None), getattr(args, "skip_wiring_checks", False)
    with phase(f"read {path}"):
        signals = read_log(path, channels=channels, wiring_checks=not skip)
    log_signals(signals, channels)
    return signals


def check_logs_exist(paths, option: str) -> None:
    """A one-line error for the first of ``paths`` (given to ``option``) that is not a file,
    before any long computation."""
    for path in map(Path, paths):
        if not path.is_file():
            what = "a folder, not a log file" if path.is_dir() else "no such log file"
            raise ValueError(f"{path}: {what} ({option})")


def refuse_unused(args: argparse.Namespace, unused: dict[str, object], where: str) -> None:
    """A one-line error naming the options of ``unused`` (option: its default) given with
    another value, which ``where`` (e.g. ``study iso-dlc``) does not use: an accepted
    option acts or is refused, before any work."""
    given = [
        option
        for option, default in unused.items()
        if getattr(args, option.lstrip("-").replace("-", "_")) not in (default, None, False)
    ]
    if given:
        verb, them = ("is", "it") if len(given) == 1 else ("are", "them")
        raise ValueError(f"{', '.join(given)} {verb} not used by {where}: leave {them} out")
