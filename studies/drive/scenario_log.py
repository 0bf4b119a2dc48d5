"""Write a simulated log (CSV or Parquet by suffix) and its JSON metadata sidecar.

Log columns (DESIGN.md): ``t vx ax ay az wx wy wz d_* v_* az_* fz_*``, then, when the
frame has them (:data:`WHEEL_COLUMNS`), the tyre-force channels: the front road-wheel
angle ``steer`` [rad, > 0 to the left], wheel spins ``omega_*`` [rad/s], the drive/brake
torque on each wheel ``torque_*`` [N m, > 0 forward] and the reference tyre forces
``fx_* fy_*`` [N] in each tyre's frame (ISO 8855: x along the wheel heading in the road
plane, y to its left; the plant's ``fz_*`` is along the road normal). The metadata
``LOG.meta.json`` records everything that produced the log.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pandas as pd

from wheelload.estimators.logs.output_files import atomic_write, write_text
from wheelload.models.conventions import WHEELS

LOG_COLUMNS = (
    ("t", "vx", "ax", "ay", "az", "wx", "wy", "wz")
    + tuple(f"d_{w}" for w in WHEELS)
    + tuple(f"v_{w}" for w in WHEELS)
    + tuple(f"az_{w}" for w in WHEELS)
    + tuple(f"fz_{w}" for w in WHEELS)
)
#: Optional channels of the tyre-force estimators, written when the frame has them.
WHEEL_COLUMNS = (
    ("steer",)
    + tuple(f"omega_{w}" for w in WHEELS)
    + tuple(f"torque_{w}" for w in WHEELS)
    + tuple(f"fx_{w}" for w in WHEELS)
    + tuple(f"fy_{w}" for w in WHEELS)
)
SUFFIXES = (".csv", ".parquet")


def file_hash(path: str | Path) -> str:
    """SHA-256 of a file's bytes, hex."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def metadata_path(log: str | Path) -> Path:
    """``LOG.meta.json`` beside the log."""
    log = Path(log)
    return log.with_name(log.name + ".meta.json")


def write_log(
    frame: pd.DataFrame, path: str | Path, metadata: dict, *, replace: bool = False
) -> Path:
    """Write the log columns of ``frame`` to ``path`` and the metadata sidecar; return its path.

    Both files are written to a temporary file and renamed into place; an
    existing file is replaced only with ``replace``.
    """
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise ValueError(f"log file '{path}' must end in one of {', '.join(SUFFIXES)}")
    missing = [c for c in LOG_COLUMNS if c not in frame.columns]
    if missing:
        raise ValueError(f"log frame lacks column '{missing[0]}'")
    path.parent.mkdir(parents=True, exist_ok=True)
    log = frame.loc[:, [*LOG_COLUMNS, *(c for c in WHEEL_COLUMNS if c in frame.columns)]]
    with atomic_write(path, replace=replace) as temporary:
        if path.suffix.lower() == ".csv":
            log.to_csv(temporary, index=False, float_format="%.9g")
        else:
            log.to_parquet(temporary, index=False)
    sidecar = metadata_path(path)
    write_text(sidecar, json.dumps(metadata, indent=2, sort_keys=True) + "\n", replace=replace)
    return sidecar
