"""Partial sensor sets on one log: each mode's accuracy and sigma, and the roll-split sweep.

Every mode is made from the full log by removing channels (a dead sensor is a
channel with no sample), so all modes meet the same drive and reference.
The IMU-only sweep runs the filter with ``suspension.roll_split_front`` set
to each value and scores the front and rear lateral load differences
:math:`F_L - F_R` by their RMS error relative to the reference's RMS.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pandas as pd

from wheelload.estimators import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import Vehicle
from wheelload.models.conventions import WHEELS
from wheelload.studies.metrics import wheel_metrics

TRAVEL = [f"d_{w}" for w in WHEELS] + [f"v_{w}" for w in WHEELS]


def _dead(wheels: tuple[str, ...]) -> Callable[[pd.DataFrame], pd.DataFrame]:
    def edit(frame: pd.DataFrame) -> pd.DataFrame:
        frame = frame.copy()
        frame[[f"{kind}_{w}" for w in wheels for kind in ("d", "v")]] = np.nan
        return frame

    return edit


def _without(*names: str) -> Callable[[pd.DataFrame], pd.DataFrame]:
    """The log without the columns ``names`` (those it has: a log without ``az`` assumes
    g in every mode, :func:`absent_channels`)."""
    return lambda frame: frame.drop(columns=[n for n in names if n in frame.columns])


def _rear_wheel_speeds(frame: pd.DataFrame) -> pd.DataFrame:
    if "vx" not in frame.columns:
        return frame
    return frame.drop(columns=["vx"]).assign(ws_rl=frame.vx, ws_rr=frame.vx)


MODES: dict[str, Callable[[pd.DataFrame], pd.DataFrame]] = {
    "full": lambda f: f,
    "IMU-only": _without(*TRAVEL),
    "one per axle (FL, RL)": _dead(("fr", "rr")),
    "front pair (FL, FR)": _dead(("rl", "rr")),
    "dead corner (RR)": _dead(("rr",)),
    "no az": _without("az"),
    "no vx, no wheel speeds": _without("vx"),
    "vx from rear wheel speeds": _rear_wheel_speeds,
    "IMU-only, no az, no vx": _without(*TRAVEL, "az", "vx"),
}


def absent_channels(frame: pd.DataFrame) -> list[str]:
    """A line per channel a mode removes that the log has not (its modes then equal
    others'): ``az`` is assumed g, ``vx`` taken from the wheel speeds or left out."""
    notes = []
    if "az" not in frame.columns:
        notes.append("the log has no az: every mode assumes az = g (flag AZ_ASSUMED_G)")
    if "vx" not in frame.columns:
        notes.append("the log has no vx: every mode runs without it (no vx: no aero terms)")
    return notes


def sensor_set_table(frame: pd.DataFrame, vehicle: Vehicle, source: str) -> pd.DataFrame:
    """One row per mode: the mode named by the signals, pooled RMSE, max and last sigma."""
    rows = []
    for name, edit in MODES.items():
        signals = signals_from_frame(edit(frame), source=f"{source} ({name})")
        estimate = build("kf", vehicle).run(signals)
        metrics = wheel_metrics(estimate.loads, signals.reference, source=source)
        rows.append({
            "mode": name,
            "named in the summary": signals.mode(),
            "finite": bool(np.isfinite(estimate.loads).all()),
            "RMSE pooled [N]": metrics.loc["pooled", "RMSE"],
            "Max [N]": metrics.loc["pooled", "Max"],
            "max sigma [N]": float(estimate.std.max()),
            "last sigma [N]": float(estimate.std[-1].max()),
        })  # fmt: skip
    return pd.DataFrame(rows)


def split_sweep(frame: pd.DataFrame, vehicle: Vehicle, splits: list[float]) -> pd.DataFrame:
    """IMU-only: relative RMS error of the front and rear lateral load differences per split."""
    signals = signals_from_frame(_without(*TRAVEL)(frame), source="IMU-only")
    reference = signals.reference
    rows = []
    for split in splits:
        suspension = dataclasses.replace(vehicle.suspension, roll_split_front=split)
        estimate = build("kf", vehicle.replace(suspension=suspension)).run(signals)
        row = {"roll_split_front": split}
        for axle, (left, right) in (("front", (0, 1)), ("rear", (2, 3))):
            truth = reference[:, left] - reference[:, right]
            error = estimate.loads[:, left] - estimate.loads[:, right] - truth
            row[f"{axle} dF error [%]"] = 100 * np.sqrt(np.mean(error**2) / np.mean(truth**2))
        row["max sigma [N]"] = float(estimate.std.max())
        rows.append(row)
    return pd.DataFrame(rows)


def reference_split(frame: pd.DataFrame, vehicle: Vehicle) -> float:
    """The log's own front share of the lateral load transfer (least squares)."""
    reference = frame[[f"fz_{w}" for w in WHEELS]].to_numpy()
    front = 0.5 * vehicle.geometry.track_front * (reference[:, 0] - reference[:, 1])
    rear = 0.5 * vehicle.geometry.track_rear * (reference[:, 2] - reference[:, 3])
    return float(np.sum(front * (front + rear)) / np.sum((front + rear) ** 2))
