"""The command line imports only the module of the command it runs (cold start)."""

import argparse
import importlib

from wheelload.studies.cli import CATALOG, COMMAND_MODULES, COMMANDS, build_parser


def test_each_command_is_registered_by_the_module_named_for_it():
    registered = {}
    for module in COMMANDS:
        parser = argparse.ArgumentParser()
        subparsers = parser.add_subparsers(dest="command")
        importlib.import_module(module).register(subparsers)
        registered.update(dict.fromkeys(subparsers.choices, module))
    assert registered == COMMAND_MODULES


def _built(parser: argparse.ArgumentParser) -> dict[str, bool]:
    """Each command listed, and whether its module built its parser (its TRAITS are set)."""
    action = _subparsers_action(parser)
    return {name: sub.get_default("traits") is not None for name, sub in action.choices.items()}


def test_a_command_builds_its_own_parser_only_and_help_builds_none():
    only = _built(build_parser(["-v", "estimate", "--example"]))
    assert list(only) == list(COMMAND_MODULES)  # every command listed, in the catalog's order
    assert [name for name, built in only.items() if built] == ["estimate"]
    assert not any(_built(build_parser(["--help"])).values())
    assert all(_built(build_parser()).values())  # no argv: every parser, for the tests' walks


def test_the_help_lists_every_command_with_the_summary_its_module_registers():
    listed = {a.dest: a.help for a in _subparsers_action(build_parser(["--help"]))._choices_actions}
    registered = {a.dest: a.help for a in _subparsers_action(build_parser())._choices_actions}
    assert listed == registered == {name: c.summary for name, c in CATALOG.items()}


def _subparsers_action(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
