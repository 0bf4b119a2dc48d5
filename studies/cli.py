"""The ``wheelload`` console command: one sub-command per module.

Each module named in :data:`COMMANDS` exposes ``register(subparsers)``, which
adds its sub-parser and sets ``handler`` (a function of the parsed arguments
returning an exit status).

A mistake a user can make is one line on stderr and exit status 2. Ctrl-C
(SIGINT) is the line ``wheelload COMMAND: interrupted`` and status 130, also where an
extension swallowed the KeyboardInterrupt and what it handed back then failed, or caught
the signal itself (:mod:`wheelload.models.runtime.interrupts`); SIGTERM
raises :class:`Terminated` in the main thread, so that every ``finally`` runs
(temporary files are removed, :mod:`wheelload.models.runtime.temporaries`), then the
line ``terminated`` and status 143.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Sequence

from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import log_level, told
from wheelload.studies.deferred import defer

#: The modules that register the commands, in the order the help lists them.
COMMANDS = tuple(command.module for command in CATALOG.values())

#: The module that registers each command: ``wheelload COMMAND ...`` imports that one
#: only (a cold start pays for what it runs; tests/cli/test_cli_commands.py keeps it exact).
COMMAND_MODULES = {name: command.module for name, command in CATALOG.items()}


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The command line. Without ``argv`` every command's module builds its parser; with
    ``argv``, only the command it names does (none for ``--help`` or ``--version``), and the
    others are listed by their summaries alone (:mod:`wheelload.studies.commands`)."""
    parser = argparse.ArgumentParser(
        prog="wheelload",
        description="Wheel normal-load estimation from suspension travel and IMU signals.",
    )
    parser.add_argument("--version", action=_Version, help="show the version and exit")
    parser.add_argument(
        "-q", "--quiet", dest="quiet_top", action="store_true", help="only the results and errors"
    )
    parser.add_argument(
        "-v", "--verbose", dest="verbose_top", action="count", help="more on stderr (-vv debug)"
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    built = set(CATALOG) if argv is None else {_command_of(argv)}
    for name, command in CATALOG.items():
        if name in built:
            importlib.import_module(command.module).register(subparsers)
        else:  # listed in the help; never parses (argv does not name it)
            subparsers.add_parser(name, help=command.summary, add_help=False)
    if argv is None:  # every parser whole, those a command builds on first use too
        _build_arguments(parser)
    return parser


def _build_arguments(parser: argparse.ArgumentParser) -> None:
    """Build ``parser``'s sub-parsers' arguments where they wait for first use (``wheelload
    bench WHAT``: ``DeferredParser.build_arguments``), all the way down."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                if hasattr(child, "build_arguments"):
                    child.build_arguments()
                _build_arguments(child)


def _command_of(argv: Sequence[str]) -> str | None:
    """The command ``argv`` names: its first word that is not an option (no top-level option
    takes a value)."""
    word = next((word for word in argv if not word.startswith("-")), None)
    return word if word in CATALOG else None


class _Version(argparse.Action):
    """``--version``: the installed distribution's version, looked up only when asked
    (``importlib.metadata`` is slow to import)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, help=None) -> None:
        super().__init__(option_strings, dest=dest, default=argparse.SUPPRESS, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        from importlib.metadata import version

        print(f"wheelload {version('wheelload')}")
        parser.exit()


class Terminated(BaseException):
    """Raised in the main thread on SIGTERM (not an ``Exception``: nothing swallows it)."""


def _terminate(signum, frame) -> None:
    raise Terminated


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``wheelload ARGV`` (default: the process's arguments, as the console command)."""
    process = argv is None  # the console command: the process ends with the command
    argv = list(sys.argv[1:] if argv is None else argv)
    defer("casadi")  # imported where a model is built, not by a warm estimate (deferred.py)
    command = _command_of(argv) or "command"
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None
    # Ctrl-C counted where it raises KeyboardInterrupt (not where a shell ignores it).
    counted = main_thread and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    try:
        return _main(argv, process=process, counted=counted)
    except KeyboardInterrupt:
        print(f"wheelload {command}: interrupted", file=sys.stderr)
        return 130
    except Terminated:
        print(f"wheelload {command}: terminated", file=sys.stderr)
        return 143
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)
        if counted:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def _configure_logging(level: int) -> None:
    """One stderr handler for the library's loggers, at the ``-q``/``-v`` level; Python
    warnings (NumPy's among them) go through it too."""
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(levelname)s: %(message)s"))
    root = logging.getLogger("wheelload")
    root.handlers[:] = [handler]
    root.setLevel(level)
    root.propagate = False
    logging.captureWarnings(True)
    warnings_logger = logging.getLogger("py.warnings")
    warnings_logger.handlers[:] = [handler]
    warnings_logger.setLevel(level)
    warnings_logger.propagate = False


def _main(argv: list[str], *, process: bool, counted: bool) -> int:
    with _startup_objects():
        parser = build_parser(argv)
    try:
        return _run(parser, argv, counted=counted)
    finally:
        if not process:  # a caller in Python gets its objects back for collection
            gc.unfreeze()


@contextlib.contextmanager
def _startup_objects():
    """Building the parser imports the command's modules: objects that live to the end and no
    garbage. The cyclic collector pauses meanwhile, and what exists then is frozen
    (``gc.freeze``): the command's collections skip it, and so does the collection at the
    console command's exit (:func:`main` unfreezes it for a caller in Python)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
    gc.freeze()


def _run(parser: argparse.ArgumentParser, argv: list[str], *, counted: bool) -> int:
    """Parse ``argv`` and run the command; Ctrl-C presses counted meanwhile when ``counted``
    (:mod:`wheelload.models.runtime.interrupts`), and an error after a press is the press."""
    args, unknown = parser.parse_known_args(argv)
    # After --help and --version: casadi (the build folder), the estimators' and models' faces.
    from wheelload.models.runtime import interrupts
    from wheelload.models.runtime.build_folder import BuildFolderError

    if unknown:  # the command's own usage, not the top level's
        subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        subparsers.choices[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    _configure_logging(log_level(args))
    interrupts.reset()
    if counted:  # main() puts Python's default handler back
        signal.signal(signal.SIGINT, interrupts.handler)
    try:
        code = int(args.handler(args) or 0)
        interrupts.check()  # a press an extension swallowed never ends in a success
        told(args)  # the lines held back while the arguments were checked
        return code
    except (ValueError, FileNotFoundError, BuildFolderError) as error:
        if interrupts.pressed():  # what a swallowed Ctrl-C left behind
            raise KeyboardInterrupt from error
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
    except Exception as error:
        if not interrupts.pressed():
            raise
        raise KeyboardInterrupt from error  # e.g. the None a swallowed Ctrl-C left behind


if __name__ == "__main__":
    sys.exit(main())
