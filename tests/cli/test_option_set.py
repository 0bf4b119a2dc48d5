"""One option set: every sub-command's parser carries the shared groups its traits declare.

Each command module declares what it reads and writes once (``TRAITS``,
:class:`~wheelload.studies.commands.options.CommandTraits`); the walk below checks
every parser, bench's included, against the declaration, and the runs below check the
declarations against what the commands do with real files.
"""

import argparse
import logging
import shutil

import pandas as pd
import pytest

from wheelload.models import example_vehicle_path
from wheelload.studies.cli import COMMAND_MODULES, build_parser, main
from wheelload.studies.pipeline.example_log import example_log_path

#: The groups' titles, as ``wheelload COMMAND --help`` shows them.
GROUPS = {
    "log": "log input",
    "scores": "scoring window",
    "vehicle": "vehicle file",
    "writes": "output",
    "many_logs": "many logs",
    "messages": "messages",
}
OPTIONS = {
    "log": ("--channels", "--skip-wiring-checks"),
    "scores": ("--start", "--end"),
    "vehicle": ("--allow-unusual",),
    "writes": ("--force",),
    "many_logs": ("--workers", "--dask", "--no-progress"),
}


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _groups(parser: argparse.ArgumentParser) -> dict[str, set[str]]:
    return {
        group.title: {s for action in group._group_actions for s in action.option_strings}
        for group in parser._action_groups
    }


@pytest.mark.parametrize("name", sorted(COMMAND_MODULES))
def test_every_command_takes_the_groups_its_traits_declare(name):
    parser = _subparsers(build_parser())[name]
    traits = parser.get_default("traits")  # the command module's TRAITS
    assert traits is not None, name
    groups = _groups(parser)
    assert {"-q", "-v"} <= groups[GROUPS["messages"]], name
    for trait, options in OPTIONS.items():
        if getattr(traits, trait):
            assert set(options) <= groups[GROUPS[trait]], (name, trait)
        else:  # an option of an undeclared group would be one the walk cannot see
            present = {s for action in parser._actions for s in action.option_strings}
            assert not set(options) & present - {"--force"}, (name, trait)


def test_bench_subcommands_take_the_message_options_and_are_listed():
    bench = _subparsers(build_parser())["bench"]
    benchmarks = _subparsers(bench)
    assert len(benchmarks) >= 9
    for name, parser in benchmarks.items():
        options = {s for action in parser._actions for s in action.option_strings}
        assert {"-q", "-v"} <= options, name
    top = build_parser().format_help()
    assert "wheelload bench --help lists them" in top


def test_the_reading_commands_read_the_logs_declared():
    """The declarations hold: every command that reads a user's log says so."""
    readers = {"estimate", "compare", "sensor-sets", "study", "weigh", "identify", "tune"}
    parsers = _subparsers(build_parser())
    for name in readers:
        assert parsers[name].get_default("traits").log, name


@pytest.fixture(scope="module")
def renamed(tmp_path_factory):
    """The bundled log with a logger's names, and a channel map back to the library's."""
    folder = tmp_path_factory.mktemp("renamed")
    frame = pd.read_csv(example_log_path(), comment="#")
    names = {c: f"LOGGER_{c}" for c in frame.columns if c != "t"}
    frame.rename(columns=names).to_csv(folder / "logger.csv", index=False)
    lines = ['[clock]\nchannel = "ax"\n\n[time]\nsource = "t"\nunit = "s"\n']
    units = {"ax": "m/s^2", "ay": "m/s^2", "az": "m/s^2", "vx": "m/s"}
    for column in names:
        unit = units.get(column) or (
            "m" if column.startswith("d_") else "m/s" if column.startswith("v_")
            else "rad/s" if column.startswith("w") else "N" if column.startswith("fz_")
            else "m/s^2"
        )  # fmt: skip
        lines.append(f'[channels.{column}]\nsource = "{names[column]}"\nunit = "{unit}"\n')
    (folder / "map.toml").write_text("\n".join(lines))
    shutil.copy(example_log_path(), folder / "original.csv")
    return folder


def _table(capsys) -> str:
    text = capsys.readouterr().out
    return text[text.index("RMSE [N]") : text.index("time per sample")]


def test_compare_reads_a_logger_log_through_its_channel_map(renamed, capsys):
    """The error table of the renamed log read through the map equals the original's."""
    vehicle = str(example_vehicle_path())
    common = ["--vehicle", vehicle, "--methods", "kf,C", "--repeat", "1"]
    assert main(["compare", str(renamed / "original.csv"), *common]) == 0
    original = _table(capsys)
    args = ["compare", str(renamed / "logger.csv"), *common]
    assert main([*args, "--channels", str(renamed / "map.toml")]) == 0
    assert _table(capsys) == original
    assert main(args) == 2  # without the map: the one-line error names the fix
    assert "give a channel map, --channels" in capsys.readouterr().err  # the fix


def test_an_unknown_option_shows_the_commands_usage(renamed, capsys):
    log = str(renamed / "original.csv")
    with pytest.raises(SystemExit) as stop:
        main(["tune", log, "--vehicle", str(example_vehicle_path()), "--out", "x.toml", "--bogus"])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: wheelload tune")
    assert "unrecognized arguments: --bogus" in err


def test_version_names_the_program(capsys):
    """``wheelload --version`` is the installed distribution's version (there is no
    top-level module to carry a ``__version__``)."""
    from importlib.metadata import version

    with pytest.raises(SystemExit):
        main(["--version"])
    out = capsys.readouterr().out.strip()
    assert out == f"wheelload {version('wheelload')}"


def test_verbose_shows_what_is_read_and_quiet_hides_it(renamed, capsys):
    vehicle = str(example_vehicle_path())
    log = str(renamed / "original.csv")
    args = ["compare", log, "--vehicle", vehicle, "--methods", "C", "--repeat", "1"]
    assert main([*args, "-v"]) == 0
    assert f"INFO: read {log}" in capsys.readouterr().err
    assert main(["-q", *args]) == 0
    assert "INFO" not in capsys.readouterr().err
    assert logging.getLogger("wheelload").level == logging.ERROR


def test_allow_unusual_reaches_the_vehicle_loader(tmp_path, capsys):
    """A 15x front spring (ride frequency beyond 5 Hz) is refused by compare, and runs with
    --allow-unusual."""
    text = example_vehicle_path().read_text()
    unusual = tmp_path / "stiff.toml"
    unusual.write_text(text.replace("spring_rate = 60000.0", "spring_rate = 900000.0", 1))
    args = ["compare", str(example_log_path()), "--vehicle", str(unusual), "--methods", "C"]
    assert main([*args, "--repeat", "1"]) == 2
    assert "--allow-unusual" in capsys.readouterr().err
    assert main([*args, "--repeat", "1", "--allow-unusual"]) == 0
    assert "RMSE [N]" in capsys.readouterr().out


def test_tune_writes_an_unusual_file_it_was_allowed_to_read(tmp_path, capsys):
    """--allow-unusual holds for the written copy's check too, not only for the input."""
    text = example_vehicle_path().read_text()
    unusual = tmp_path / "stiff.toml"
    unusual.write_text(text.replace("spring_rate = 60000.0", "spring_rate = 900000.0", 1))
    out = tmp_path / "tuned.toml"
    args = ["tune", str(example_log_path()), "--vehicle", str(unusual), "--out", str(out)]
    assert main([*args, "--iterations", "2", "--allow-unusual"]) == 0
    assert "spring_rate = 900000.0" in out.read_text()
