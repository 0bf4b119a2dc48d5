"""Every source folder is packaged: an unlisted folder would silently miss the wheel."""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_python_folder_is_a_listed_package():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    listed = set(config["tool"]["setuptools"]["packages"])
    folders = {
        "wheelload." + ".".join(path.parent.relative_to(ROOT).parts)
        for path in ROOT.rglob("*.py")
        if path.parent != ROOT
        and path.parent.relative_to(ROOT).parts[0] in ("models", "estimators", "studies")
        and "__pycache__" not in path.parts
    }
    assert folders == listed


def test_the_packages_ship_their_typing_marker():
    """PEP 561: ``wheelload`` is a namespace package (the repository's top level holds no
    ``__init__``), so ``py.typed`` sits in each of its packages, listed as package data."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    data = config["tool"]["setuptools"]["package-data"]
    for package in ("models", "estimators", "studies"):
        assert (ROOT / package / "py.typed").is_file()
        assert "py.typed" in data[f"wheelload.{package}"]
    assert not (ROOT / "__init__.py").exists()


def test_installed_package_is_importable_under_one_name():
    import wheelload.estimators
    import wheelload.models
    import wheelload.studies

    assert Path(wheelload.models.__file__).resolve().parent == ROOT / "models"
