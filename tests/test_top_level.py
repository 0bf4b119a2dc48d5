"""``import wheelload``: the version and the main names, each imported on first use."""

import json
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import wheelload
import wheelload.estimators
import wheelload.models

ROOT = Path(__file__).resolve().parent.parent


def test_the_version_is_the_installed_distributions():
    assert wheelload.__version__ == metadata.version("wheelload")
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert wheelload.__version__ == config["project"]["version"]


def test_the_main_names_are_the_faces_own():
    for name in wheelload.__all__:
        if name != "__version__":
            face = (
                wheelload.estimators if name in wheelload.estimators.__all__ else wheelload.models
            )
            assert getattr(wheelload, name) is getattr(face, name), name
    assert {"build", "methods", "read_log", "load_vehicle", "Estimate"} <= set(dir(wheelload))


def test_importing_the_top_level_imports_nothing_it_names():
    """A fresh interpreter: ``import wheelload`` imports no face, no CasADi and not the
    metadata reader; asking for ``build`` imports the estimators' face."""
    code = (
        "import json, sys, wheelload\n"
        "before = sorted(sys.modules)\n"
        "wheelload.build\n"
        "print(json.dumps([before, sorted(sys.modules)]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    before, after = (set(names) for names in json.loads(done.stdout))
    for heavy in ("casadi", "importlib.metadata", "wheelload.estimators", "wheelload.models"):
        assert heavy not in before, heavy
    assert "wheelload.estimators" in after


def test_dir_of_a_face_shows_its_public_names():
    shown = dir(wheelload.estimators)
    assert set(wheelload.estimators.__all__) <= set(shown)
    assert {"build", "method", "methods", "Estimator", "MethodInfo", "KfOptions"} <= set(shown)
    assert "lazy_names" not in shown
    assert set(wheelload.models.__all__) <= set(dir(wheelload.models))
