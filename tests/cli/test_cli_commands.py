"""The command line imports only the module of the command it runs (cold start)."""

import argparse
import importlib

from wheelload.studies.cli import COMMAND_MODULES, COMMANDS, build_parser


def test_each_command_is_registered_by_the_module_named_for_it():
    registered = {}
    for module in COMMANDS:
        parser = argparse.ArgumentParser()
        subparsers = parser.add_subparsers(dest="command")
        importlib.import_module(module).register(subparsers)
        registered.update(dict.fromkeys(subparsers.choices, module))
    assert registered == COMMAND_MODULES


def test_a_command_builds_its_own_parser_only_and_help_builds_all():
    only = build_parser(["estimate", "--example"])
    (action,) = [a for a in only._actions if isinstance(a, argparse._SubParsersAction)]
    assert list(action.choices) == ["estimate"]
    full = build_parser(["--help"])
    (action,) = [a for a in full._actions if isinstance(a, argparse._SubParsersAction)]
    assert set(action.choices) == set(COMMAND_MODULES)
