"""The bundled example log (sports car): ``studies/data/example_drive.csv``."""

from __future__ import annotations

from importlib import resources
from pathlib import Path


def example_log_path() -> Path:
    """The bundled example log (sports car, see studies/data/README.md)."""
    return Path(str(resources.files("wheelload.studies") / "data" / "example_drive.csv"))
