"""One meaning per option name: every parser the console command builds (bench's
benchmarks included) is walked, and an option name shared by several commands must take
the same kind of value (a flag, a number or a text/path), say the same thing in its help,
and ``--workers`` must default alike; every ``--out`` declares its kind (file, folder,
prefix) in its metavar and its help. The kinds are tabled in
``studies/docs/pages/guide/command-line.md``.
"""

import argparse
import re
from collections import defaultdict
from pathlib import Path

import pytest

from wheelload.studies.cli import build_parser

#: What every help of a shared option says (any one of the words, case-insensitive).
MEANINGS = {
    "--allow-unusual": ("physical ranges",),
    "--channels": ("channel map",),
    "--dask": ("dask",),
    "--end": ("up to this time",),
    "--force": ("replace",),
    "--help": ("help",),
    "--horizon": ("window",),
    "--horizons": ("window",),
    "--instrumental": ("least squares",),
    "--internal-rate": ("integration rate",),
    "--log": ("log",),
    "--log-count": ("number of logs",),
    "--methods": ("method names",),
    "--model": ("model",),
    "--no-dask": ("dask",),
    "--no-progress": ("progress",),
    "--noise": ("noise",),
    "--out": ("file", "folder", "prefix"),
    "--plot": ("figure",),
    # a shorter run; what it keeps is each command's, said in its help
    "--quick": ("only", "cut", "short", "few", "tiled", "logs of"),
    "--quiet": ("errors",),
    "--rate": ("rate [hz]",),
    "--repeat": ("runs",),
    "--repeats": ("repeat", "rounds", "runs"),
    "--robust": ("robust",),
    "--samples": ("sample", "log sizes"),
    "--scenario": ("scenario",),
    "--seed": ("seed",),
    "--skip-wiring-checks": ("wiring",),
    "--start": ("from this time",),
    "--suspension": ("vehicle model",),
    "--template": ("template",),
    "--vehicle": ("vehicle",),
    "--verbose": ("more on stderr",),
    "--workers": ("processes", "worker"),
}
#: ``--out``'s metavar and the words its help opens with, kind by kind.
OUT_KINDS = {
    "FILE": ("file",),
    "DIR": ("folder",),
    "FILE|DIR": ("file", "folder"),
    "PREFIX|DIR": ("prefix", "folder"),
}


def _parsers() -> dict[str, argparse.ArgumentParser]:
    """Every parser by its command line (``wheelload``, ``wheelload bench kf`` ...)."""
    found = {}

    def walk(parser: argparse.ArgumentParser, name: str) -> None:
        found[name] = parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub, child in action.choices.items():
                    walk(child, f"{name} {sub}")

    walk(build_parser(), "wheelload")
    return found


def _options() -> dict[str, list[tuple[str, argparse.Action]]]:
    options = defaultdict(list)
    for name, parser in _parsers().items():
        for action in parser._actions:
            for option in action.option_strings:
                if option.startswith("--"):
                    options[option].append((name, action))
    return options


def _value_kind(action: argparse.Action) -> str:
    """flag (takes no value), number (int or float) or text (a name, a path, a list)."""
    if action.nargs == 0:
        return "flag"
    if action.type in (int, float):
        return "number"
    return "text"


def test_the_walk_sees_every_command_and_benchmark():
    names = set(_parsers())
    assert {"wheelload estimate", "wheelload study", "wheelload bench kf"} <= names
    assert len(names) >= 30


SHARED = sorted(option for option, uses in _options().items() if len(uses) > 1)


@pytest.mark.parametrize("option", SHARED)
def test_a_shared_option_name_has_one_kind_of_value(option):
    kinds = {(name, _value_kind(action)) for name, action in _options()[option]}
    assert len({kind for _, kind in kinds}) == 1, sorted(kinds)


@pytest.mark.parametrize("option", SHARED)
def test_a_shared_option_name_says_one_meaning(option):
    assert option in MEANINGS, f"{option}: shared by several commands; table its meaning"
    for name, action in _options()[option]:
        text = (action.help or "").lower()
        assert any(word in text for word in MEANINGS[option]), (name, option, action.help)


def test_every_out_declares_its_kind():
    uses = _options()["--out"]
    assert len(uses) >= 9
    for name, action in uses:
        assert action.metavar in OUT_KINDS, (name, action.metavar)
        words = OUT_KINDS[action.metavar]
        text = action.help.lower()
        assert text.startswith(words[0]), (name, action.help)  # the kind first
        assert all(word in text for word in words), (name, action.help)


def test_workers_has_one_default_stated_in_its_help():
    """``--workers N`` (one count; bench logs' is a list of counts to time) defaults alike."""
    single = [(n, a) for n, a in _options()["--workers"] if a.nargs is None]
    assert {n for n, _ in single} >= {"wheelload estimate", "wheelload study"}
    assert {a.default for _, a in single} == {1}
    assert all("(default 1" in a.help for _, a in single)


def test_the_guide_tables_every_out_kind():
    """The guide's ``--out`` table puts each command in its kind's row."""
    page = Path(__file__).parents[2] / "studies/docs/pages/guide/command-line.md"
    rows = {
        line.split("`")[1].replace("\\|", "|"): line
        for line in page.read_text(encoding="utf-8").splitlines()
        if line.startswith("| `") and line.split("`")[1].replace("\\|", "|") in OUT_KINDS
    }
    assert set(rows) == set(OUT_KINDS)
    for name, action in _options()["--out"]:
        command = name.removeprefix("wheelload ")
        row = rows[action.metavar].split("|")[-2]  # the commands column
        assert re.search(rf"(?<![\w-]){re.escape(command)}(?![\w-])", row), (command, row)
