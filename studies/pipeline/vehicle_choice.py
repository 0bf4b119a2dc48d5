"""Which vehicle file a command runs on, said aloud: ``--vehicle``, or the bundled sports
car, and never the bundled car on a user's log.

A command that scores or estimates a log needs the car the log was recorded on; the
bundled sports car is right only for the bundled example log and for logs simulated on it
(their ``LOG.meta.json`` names the car, :func:`~wheelload.studies.drive.scenario_log.
metadata_path`). Any other log without ``--vehicle`` is refused with the fix, before any
work: the sports car's numbers on a 1390 kg car's log (a pooled RMSE of 814 N) look like
a result and are not one. Where no user log is involved (a simulation, a study on the
plant) the bundled car is used and named (:func:`bundled_line`).
"""

from __future__ import annotations

import json
import tomllib
from collections.abc import Iterable
from pathlib import Path

from wheelload.models import example_vehicle_path
from wheelload.studies.pipeline.example_log import example_log_path


def bundled_name() -> str:
    """The bundled sports car's ``name`` (read from its file, without building a model)."""
    with open(example_vehicle_path(), "rb") as file:
        return str(tomllib.load(file)["name"])


def bundled_line(command: str) -> str:
    """The line telling that ``command`` runs on the bundled sports car, and how not to."""
    return (
        f"wheelload {command}: vehicle: the bundled sports car '{bundled_name()}' "
        f"({example_vehicle_path()}); give --vehicle FILE for another"
    )


def from_bundled_car(log: str | Path) -> bool:
    """Whether ``log`` was recorded on the bundled sports car: the bundled example log, or
    a simulated log whose ``LOG.meta.json`` names the car."""
    path = Path(log)
    if path.exists() and path.resolve() == example_log_path().resolve():
        return True
    sidecar = path.with_name(path.name + ".meta.json")
    try:
        metadata = json.loads(sidecar.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(metadata, dict) and metadata.get("vehicle") == bundled_name()


def vehicle_for_logs(vehicle: str | None, logs: Iterable[str | Path], command: str) -> Path:
    """The ``--vehicle`` file, or the bundled car's when every log was recorded on it.

    A ``ValueError`` (one line, with the fix) for a user's log without ``--vehicle`` and
    for a ``--vehicle`` file that does not exist.
    """
    if vehicle is not None:
        path = Path(vehicle)
        if not path.is_file():
            raise ValueError(f"{path}: no such vehicle file (--vehicle)")
        return path
    foreign = [str(log) for log in logs if not from_bundled_car(log)]
    if foreign:
        raise ValueError(
            f"{foreign[0]}: give --vehicle FILE, the car this log was recorded on "
            f"(without it {command} would use the bundled sports car, not meant for your log)"
        )
    return example_vehicle_path()
