"""A warm estimate reuses only what its own code and nothing else built.

The stored Functions, their signature records and the compiled libraries are
keyed by a hash of the models' and estimators' sources (a warm run reads them
without CasADi); the vehicle's numbers are inputs of the compiled C, never part
of it. Real files in child processes: a copy of the package whose model source is edited,
run with TMPDIRs of its own (so build folders of its own), must build its own libraries; a
second vehicle file must get its own estimates from the libraries this user's build folder
already holds for the first.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from wheelload.models import example_vehicle_path
from wheelload.models.runtime.function_cache import PACKAGE_ROOT

pytestmark = pytest.mark.heavy(19)  # seconds (tests/conftest.py)


def _estimate(tmpdir: Path | None, out: Path, *args: str, package: Path | None = None) -> bytes:
    """``wheelload estimate --example ARGS --out OUT`` with its build folder under ``tmpdir``
    (None: this user's) and the package from ``package`` (a folder holding ``wheelload/``);
    the estimates."""
    env = dict(os.environ) if tmpdir is None else {**os.environ, "TMPDIR": str(tmpdir)}
    if package is not None:
        env["PYTHONPATH"] = str(package)
    command = [sys.executable, "-m", "wheelload.studies.cli", "estimate", "--example", *args]
    done = subprocess.run([*command, "--out", str(out), "--force"], capture_output=True,
                          text=True, env=env)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return out.read_bytes()


def test_an_edited_model_source_never_meets_a_library_of_the_old_one(tmp_path):
    package = tmp_path / "package"
    for folder in ("models", "estimators", "studies"):
        shutil.copytree(PACKAGE_ROOT / folder, package / "wheelload" / folder)
    shared, fresh = tmp_path / "shared", tmp_path / "fresh"
    shared.mkdir()
    fresh.mkdir()
    before = _estimate(shared, tmp_path / "before.csv", package=package)
    assert _estimate(shared, tmp_path / "warm.csv", package=package) == before  # warm: same
    conventions = package / "wheelload" / "models" / "conventions.py"
    text = conventions.read_text()
    assert "GRAVITY = 9.80665" in text
    conventions.write_text(text.replace("GRAVITY = 9.80665", "GRAVITY = 9.81"))  # a new model
    after = _estimate(shared, tmp_path / "after.csv", package=package)
    cold = _estimate(fresh, tmp_path / "cold.csv", package=package)
    assert after != before  # the edit reached the numbers: nothing of the old code was used
    assert after == cold  # the same bits as a build folder that never saw the old code


def test_a_second_vehicle_file_gets_its_own_estimates(tmp_path):
    vehicle = tmp_path / "stiffer.toml"
    text = example_vehicle_path().read_text()
    assert text.count("spring_rate = 60000.0") == 1
    vehicle.write_text(text.replace("spring_rate = 60000.0", "spring_rate = 66000.0"))
    example = _estimate(None, tmp_path / "example.csv")
    lean = _estimate(None, tmp_path / "lean.csv", "--vehicle", str(vehicle))
    whole = _estimate(None, tmp_path / "whole.csv", "--vehicle", str(vehicle), "--in-memory")
    assert lean != example
    assert lean == whole  # the lean path's compiled loop and the whole-log run agree
