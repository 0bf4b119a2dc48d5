"""One figure per simulated scenario: speed, accelerations, the four reference loads, path."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from wheelload.estimators.logs.output_files import atomic_write
from wheelload.models.conventions import GRAVITY, WHEELS


def plot_scenario(
    frame: pd.DataFrame, path: str | Path, title: str, *, replace: bool = False
) -> Path:
    """Save a figure (speed; ax, ay; Fz per wheel; lateral offset) of a truth frame to ``path``.

    The offset panel needs the path columns ``n target half_width`` of the truth.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = frame["t"].to_numpy()
    fig, axes = plt.subplots(4, 1, figsize=(10, 10), sharex=True, constrained_layout=True)
    axes[0].plot(t, frame["vx"] * 3.6, color="k")
    axes[0].set_ylabel("speed [km/h]")
    axes[1].plot(t, frame["ax"], label="$a_x$")
    axes[1].plot(t, frame["ay"], label="$a_y$")
    axes[1].plot(t, frame["az"] - GRAVITY, label="$a_z - g$", alpha=0.6)
    axes[1].set_ylabel("specific force at IMU [m/s²]")
    axes[1].legend(loc="upper right", ncol=3)
    for wheel in WHEELS:
        axes[2].plot(t, frame[f"fz_{wheel}"] / 1000.0, label=wheel.upper())
    axes[2].set_ylabel("reference load $F_z$ [kN]")
    axes[2].legend(loc="upper right", ncol=4)
    axes[3].plot(t, frame["n"], color="k", label="car")
    axes[3].plot(t, frame["target"], color="C2", label="target")
    axes[3].fill_between(t, -frame["half_width"], frame["half_width"], color="0.9", label="road")
    axes[3].set_ylabel("lateral offset n [m]")
    axes[3].set_xlabel("time [s]")
    axes[3].legend(loc="upper right", ncol=3)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, replace=replace) as temporary:
        fig.savefig(temporary, dpi=110)
    plt.close(fig)
    return path
