"""Vehicle-file edit → many-logs run: the library keyed by the model structure or by the text.

One repeat edits a copy of the vehicle file (a comment line and the front spring rate scaled
by a factor new to every repeat and run, so no earlier build matches the text) and times,
from the edited file to the estimates of every log:

- ``structure``: :func:`~wheelload.estimators.codegen.batched.run_batched` (the library
  built once per model structure, the values set at run time);
- ``text``: the same run through a library built from the edited file's generated C and
  cached by that text (:func:`text_keyed_library`, how the many-logs library was cached
  before it was keyed by the structure: every edit compiles it);
- ``single``: the single-log estimate of the first log (:meth:`TwoStageKF.run`), the named
  alternative the two are set against.

Each includes reading the vehicle file and building the filter.
"""

from __future__ import annotations

import re
import secrets
import time
from dataclasses import dataclass
from pathlib import Path

import casadi as ca

from wheelload.estimators import Signals
from wheelload.estimators.codegen.batched import (
    KERNEL_FLAGS,
    PREFIX,
    SHARED_FLAGS,
    BatchLibrary,
    library_sources,
    run_batched,
    run_on_library,
)
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import load_vehicle
from wheelload.models.runtime.build_folder import shared_library

#: The value a repeat edits (the first spring rate of the file, front axle).
EDITED_KEY = re.compile(r"^(spring_rate\s*=\s*)([0-9.eE+-]+)", re.MULTILINE)


def text_keyed_library(step: ca.Function, vehicle_path: Path) -> BatchLibrary:
    """The batch library cached by its generated text (which holds the file's hash and
    values): what an edit of the file meant before the structure key."""
    sources = library_sources(step, vehicle_path)
    kernel = shared_library(sources["kernel"], PREFIX, KERNEL_FLAGS)
    driver = shared_library(sources["driver"], f"{PREFIX}_driver", SHARED_FLAGS)
    getattr(driver, f"{PREFIX}_run_batch").restype = None
    return BatchLibrary(kernel=kernel, driver=driver)


def edited_copy(vehicle_path: Path, folder: Path, repeat: int) -> Path:
    """A copy of the vehicle file with a comment line and its first spring rate scaled by
    ``1 + u 1e-3`` (``u`` random): values only, the model structure kept."""
    text = vehicle_path.read_text()
    match = EDITED_KEY.search(text)
    if match is None:
        raise ValueError(f"{vehicle_path}: no spring_rate key to edit")
    factor = 1.0 + (1 + secrets.randbelow(10**6)) * 1e-9
    value = float(match.group(2)) * factor
    text = text[: match.start(2)] + repr(value) + text[match.end(2) :]
    path = folder / f"edited_{repeat}.toml"
    path.write_text(text + f"\n# edit {repeat}: spring rate x {factor!r}\n")
    return path


@dataclass(frozen=True)
class EditTimes:
    """Seconds from an edited file to the estimates, by way (module docstring)."""

    structure: float
    text: float | None
    single: float


def time_edit(vehicle_path: Path, logs: list[Signals], *, text: bool) -> EditTimes:
    """One repeat's times for the file ``vehicle_path`` (already edited); ``text``: also the
    text-keyed way (a compile of about a minute)."""
    start = time.perf_counter()
    kf = TwoStageKF(load_vehicle(vehicle_path, allow_unusual=True))
    run_batched(kf, vehicle_path, logs)
    structure = time.perf_counter() - start
    keyed_by_text = None
    if text:
        start = time.perf_counter()
        kf = TwoStageKF(load_vehicle(vehicle_path, allow_unusual=True))
        run_on_library(text_keyed_library(kf.step_function, vehicle_path), kf, logs)
        keyed_by_text = time.perf_counter() - start
    start = time.perf_counter()
    TwoStageKF(load_vehicle(vehicle_path, allow_unusual=True)).run(logs[0])
    single = time.perf_counter() - start
    return EditTimes(structure=structure, text=keyed_by_text, single=single)
