"""Figures of an identification: fitted maps over their data (paper Fig. 2), residuals in time.

Each map is drawn from the fitted parameters' share of the prediction,
:math:`J_G \\theta_G` for the parameter group G (dampers, springs, bars),
over the partial residuals :math:`y - \\hat y + J_G \\theta_G` of the data.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wheelload.estimators.identification import DataKind, Identification  # noqa: E402
from wheelload.models.conventions import AXLES

MAX_POINTS = 4000
LEFT = {"front": "fl", "rear": "rl"}


def _group(result: Identification, prefix: str, axle: str) -> np.ndarray:
    return np.array(
        [
            j
            for j, name in enumerate(result.names)
            if name.startswith(prefix) and f"_{axle}" in name
        ],
        int,
    )


def _thin(mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    index = np.flatnonzero(mask)
    if index.size > MAX_POINTS:
        index = np.sort(rng.choice(index, MAX_POINTS, replace=False))
    return index


def plot_maps(result: Identification, path: str | Path) -> Path:
    """Damper force against velocity, spring force against travel, bar force against travel
    difference, per axle: fitted map (line) over the partial residuals of the data (dots)."""
    rows = result.rows
    residual = rows.y - rows.y_hat
    axle_of = {"fl": "front", "fr": "front", "rl": "rear", "rr": "rear"}
    rng = np.random.default_rng(0)
    figure, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    panels = (
        ("damper_", "rate", "velocity v [m/s] (> 0 compression)", "damper force [N]"),
        ("spring_", "travel", "travel d [m] (> 0 compression)", "spring force [N]"),
        ("arb_rate_", "difference", "travel difference d_L - d_R [m]", "bar force, left [N]"),
    )
    for r, axle in enumerate(AXLES):
        wheels = np.array([axle_of[w] == axle for w in rows.wheel])
        for c, (prefix, signal, xlabel, ylabel) in enumerate(panels):
            ax = axes[r, c]
            group = _group(result, prefix, axle)
            x = getattr(rows, signal)
            mask = wheels & np.isfinite(x)
            if prefix == "arb_rate_":
                mask &= rows.wheel == LEFT[axle]
            if group.size == 0 or not mask.any():
                ax.set_visible(False)
                continue
            share = rows.J[:, group] @ result.value[group]
            mask &= np.abs(rows.J[:, group]).sum(axis=1) > 0
            index = _thin(mask, rng)
            ax.plot(x[index], (residual + share)[index], ".", ms=2, alpha=0.3, label="data")
            order = index[np.argsort(x[index])]
            ax.plot(x[order], share[order], "-", color="C3", lw=1.5, label="fitted map")
            ax.set_title(f"{axle} {prefix.rstrip('_').replace('_', ' ')}")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
    figure.tight_layout()
    path = Path(path)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def plot_residuals(result: Identification, path: str | Path) -> Path | None:
    """Fit residual against time per wheel, one panel per drive log; None without drive logs."""
    drives = [g for g, d in enumerate(result.sets) if d.kind is DataKind.DRIVE]
    if not drives:
        return None
    rows = result.rows
    residual = rows.y - rows.y_hat
    figure, axes = plt.subplots(len(drives), 1, figsize=(11, 3.2 * len(drives)), squeeze=False)
    for ax, g in zip(axes[:, 0], drives):
        for wheel in result.sets[g].rows:
            mask = (rows.group == g) & (rows.wheel == wheel)
            if mask.any():
                order = np.argsort(rows.t[mask])
                ax.plot(rows.t[mask][order], residual[mask][order], lw=0.8, label=wheel.upper())
        ax.set_title(f"{result.sets[g].label()}: reference minus identified suspension model")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("residual [N]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=4)
    figure.tight_layout()
    path = Path(path)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path
