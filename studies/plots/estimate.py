"""Figures: estimated wheel loads with their 2-sigma band against the reference."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wheelload.estimators import Estimate, Signals, StepFlag  # noqa: E402

WHEEL_NAMES = ("front left", "front right", "rear left", "rear right")


def plot_estimate(estimate: Estimate, signals: Signals, path: str | Path, title: str = "") -> Path:
    """Four panels (FL, FR, RL, RR): estimate, 2-sigma band, reference; error panel below.

    Samples whose updates were skipped for missing inputs are marked.
    """
    path = Path(path)
    figure, axes = plt.subplots(
        3, 2, figsize=(12, 9), sharex=True, gridspec_kw={"height_ratios": [2, 2, 1.3]}
    )
    t = estimate.t
    flagged = (estimate.flags & StepFlag.skipped_mask()) != 0
    for i, ax in enumerate(axes[:2].ravel()):
        load = estimate.loads[:, i] / 1000.0
        band = 2.0 * estimate.std[:, i] / 1000.0
        ax.fill_between(
            t, load - band, load + band, color="tab:blue", alpha=0.2, lw=0, label="estimate ±2σ"
        )
        if signals.reference is not None:
            ax.plot(t, signals.reference[:, i] / 1000.0, color="black", lw=1.0, label="reference")
        ax.plot(t, load, color="tab:blue", lw=1.0, label="estimate")
        if flagged.any():
            ax.plot(t[flagged], load[flagged], "x", color="tab:red", ms=3, label="update skipped")
        ax.set_title(WHEEL_NAMES[i])
        ax.set_ylabel("Fz [kN]")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="best", fontsize=8)
    if signals.reference is not None:
        error = estimate.loads - signals.reference
        for i, ax in enumerate(axes[2]):
            for j in (i * 2, i * 2 + 1):
                ax.plot(t, error[:, j], lw=0.8, label=f"{WHEEL_NAMES[j]}")
            axle = error[:, 2 * i : 2 * i + 2]
            rms = (
                f"RMS {np.sqrt(np.nanmean(axle**2)):.0f} N"
                if np.isfinite(axle).any()
                else "no reference"
            )
            ax.set_title(f"error, {'front' if i == 0 else 'rear'} axle ({rms})")
            ax.set_ylabel("error [N]")
            ax.legend(loc="best", fontsize=8)
            ax.grid(alpha=0.3)
    else:
        for i, ax in enumerate(axes[2]):
            ax.plot(t, estimate.residual[:, i + 1], lw=0.8)
            ax.set_title(f"{('pitch', 'roll')[i]} constraint residual")
            ax.set_ylabel("[N m]")
            ax.grid(alpha=0.3)
    for ax in axes[2]:
        ax.set_xlabel("t [s]")
    if title:
        figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path
