"""What a cold start imports: one log's estimate pays only for what it runs.

Structural, not timed: a fresh interpreter runs ``wheelload estimate --example
--out FILE`` (the lean single-log path) and reports ``sys.modules``; none of the
modules below may be among them (each was imported once and cost start-up time).
``wheelload --help`` imports no command module at all, and ``wheelload COMMAND --help``
that command's parser only, none of the numerics it runs with.
"""

import gc
import json
import os
import re
import subprocess
import sys

import pytest

from wheelload.studies.cli import CATALOG

#: Modules the single-log path does not use: worker processes and the many-log driver,
#: the batched C, the identification fits (scipy), pandas, the MHE's OSQP, the family,
#: plotting, progress bars, MDF4, Dask, the docs, the installed version's metadata, the
#: projection KF, the channel maps, numpy.ma (np.median's first call imports it), the
#: symbolic models and the step's builder (a warm run reads them compiled).
NOT_FOR_ONE_LOG = (
    "asammdf",
    "concurrent.futures.process",
    "dask",
    "importlib.metadata",
    "matplotlib",
    "multiprocessing",
    "osqp",
    "pandas",
    "scipy",
    "tqdm",
    "wheelload.estimators.codegen",
    "wheelload.estimators.family",
    "wheelload.estimators.identification.fit",
    "wheelload.estimators.mhe.qp",
    "wheelload.studies.docs",
    "wheelload.studies.pipeline.batch",
    "wheelload.studies.plots",
    "wheelload.estimators.kf.projection",
    "wheelload.estimators.logs.readers.channel_map",
    "numpy.ma",
    "wheelload.models.equilibrium",
    "wheelload.estimators.kf.step",
)


def _modules_after(argv: list[str]) -> set[str]:
    """``sys.modules`` of a fresh interpreter after ``wheelload ARGV`` (its output dropped)."""
    return _run_fresh(argv)[1]


def _run_fresh(argv: list[str]) -> tuple[str, set[str]]:
    """What ``wheelload ARGV`` prints on stdout in a fresh interpreter, and its ``sys.modules``."""
    code = (
        "import contextlib, io, json, sys\n"
        "from wheelload.studies.cli import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        "    try:\n"
        f"        status = main({argv!r})\n"
        "    except SystemExit as end:\n"
        "        status = end.code\n"
        "print(json.dumps([status, out.getvalue(), sorted(sys.modules)]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=dict(os.environ)
    )
    assert done.returncode == 0, done.stderr
    status, output, modules = json.loads(done.stdout.strip().splitlines()[-1])
    assert status == 0, done.stderr
    return output, set(modules)


def test_one_log_imports_nothing_it_does_not_run(tmp_path):
    """A warm run (the build folder filled by the first) of one log's estimate: neither
    CasADi (a stand-in, studies/deferred.py) nor the symbolic models nor the rest above."""
    out = tmp_path / "loads.csv"
    argv = ["estimate", "--example", "--out", str(out), "--force"]
    _modules_after(argv)  # builds what the build folder lacks (that imports the models)
    modules = _modules_after(argv)
    assert out.stat().st_size > 0  # the path ran, through to the written estimates
    assert "wheelload.estimators.kf.log_stream" in modules  # the lean path, not another
    imported = sorted(m for m in (*NOT_FOR_ONE_LOG, "casadi.casadi") if m in modules)
    assert imported == []  # casadi.casadi: the extension module, loaded with casadi itself


def test_the_version_imports_no_numerics():
    modules = _modules_after(["--version"])
    loaded = ("casadi.casadi", "numpy", "pyarrow", "wheelload.models")
    assert sorted(m for m in loaded if m in modules) == []


#: What the commands run with, none of it needed to list or describe them (casadi.casadi: the
#: extension itself, "casadi" being a stand-in until used, studies/deferred.py).
HEAVY = ("casadi.casadi", "scipy", "pandas", "pyarrow", "matplotlib", "osqp", "dask")
#: The ground-truth plant, the scenarios built on it and the studies' experiments.
PLANT_AND_STUDIES = (
    "wheelload.models.plant",
    "wheelload.studies.drive.scenarios",
    "wheelload.studies.experiments.catalog",
)


def test_the_help_imports_no_command_and_lists_every_command():
    """``wheelload --help`` reads the summaries from studies/commands/__init__.py alone."""
    text, modules = _run_fresh(["--help"])
    assert sorted(m for m in HEAVY if m in modules) == []
    commands = {m for m in modules if m.startswith("wheelload.studies.commands.")}
    assert commands <= {"wheelload.studies.commands.options"}  # the table is the package itself
    assert re.findall(r"^ {4}(\S+)", text, re.MULTILINE) == list(CATALOG)  # the names, in order
    unwrapped = re.sub(r"\s+", "", text)  # the summaries as wrapped to the terminal's width
    assert [n for n, c in CATALOG.items() if re.sub(r"\s+", "", c.summary) not in unwrapped] == []


@pytest.mark.parametrize(
    "command",
    ["vehicle", "estimate", "methods", "compare", "channels", "sensor-sets", "bench", "weigh",
     "identify", "tune", "docs", "study", "identify-study"],
)  # fmt: skip
def test_a_commands_help_imports_only_its_parser(command):
    """``wheelload COMMAND --help`` builds that command's parser: none of what it runs with
    (``study`` and ``identify-study`` list their choices from studies/experiments/runs/choices.py
    and studies/drive/scenario_names.py, not from the experiments and the plant)."""
    text, modules = _run_fresh([command, "--help"])
    assert text.startswith(f"usage: wheelload {command}")
    assert sorted(m for m in HEAVY if m in modules) == []
    assert sorted(m for m in modules if m.startswith(PLANT_AND_STUDIES)) == []
    others = {c.module for name, c in CATALOG.items() if name != command}
    assert sorted(others & modules) == []


def test_the_collector_skips_the_startup_objects_and_a_caller_gets_them_back(capsys):
    """The console command freezes what building its parser made (gc.freeze: the collections
    and the exit skip it); called from Python, main() leaves the collector as it was."""
    code = (
        "import contextlib, gc, io, sys\n"
        "sys.argv = ['wheelload', 'methods']\n"
        "from wheelload.studies.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main()\n"
        "print(gc.get_freeze_count(), gc.isenabled())\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    frozen, enabled = done.stdout.split()
    assert int(frozen) > 10_000 and enabled == "True"  # the modules' objects, frozen

    from wheelload.studies.cli import main

    before = gc.get_freeze_count()
    assert main(["methods"]) == 0
    assert gc.get_freeze_count() == before and gc.isenabled()
    assert "kf" in capsys.readouterr().out
