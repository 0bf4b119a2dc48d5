"""What ``wheelload estimate`` is asked to do: the settings of each log and the logs named.

Kept apart from :mod:`~wheelload.studies.pipeline.batch` (worker processes, Dask,
the batched C) so that estimating one log imports none of that.
"""

from __future__ import annotations

import glob
from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators.logs.readers.formats import SUFFIXES
from wheelload.estimators.protocol import DEFAULT_MODEL, SuspensionModel


@dataclass(frozen=True, kw_only=True)
class EstimateSettings:
    """How each log is estimated (the command line's options)."""

    vehicle: Path
    method: str = "kf"
    channels: Path | None = None
    still_period: float | None = None
    still_noise: float | None = None
    corner_weights: str | None = None
    allow_unusual: bool = False
    wiring_checks: bool = True
    smooth: bool = False  # offline RTS smoother over the KF (kf only)
    suspension: SuspensionModel = DEFAULT_MODEL  # vehicle model of a family method


def expand_logs(patterns: list[str]) -> list[Path]:
    """Log files named by files, folders or glob patterns, sorted, without repeats."""
    found: list[Path] = []
    for pattern in patterns:
        path = Path(pattern)
        if path.is_dir():
            matches = [p for p in sorted(path.iterdir()) if p.suffix.lower() in SUFFIXES]
            if not matches:
                raise ValueError(f"{path}: folder has no log file ({', '.join(SUFFIXES)})")
        elif path.exists():
            matches = [path]
        elif glob.has_magic(pattern):
            matches = [Path(p) for p in sorted(glob.glob(pattern)) if Path(p).is_file()]
            if not matches:
                raise ValueError(f"{pattern}: no file matches")
        else:
            raise ValueError(f"{path}: no such log file")
        found += matches
    return sorted(dict.fromkeys(found))
