"""Figures of a method comparison: one per wheel, every method's estimate against the reference."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from wheelload.estimators.logs.signals import Signals  # noqa: E402
from wheelload.models.conventions import WHEELS
from wheelload.models.files.temporaries import replacing
from wheelload.studies.pipeline.comparison import Comparison  # noqa: E402

WHEEL_NAMES = ("front left", "front right", "rear left", "rear right")


def figure_paths(folder: str | Path, stem: str) -> list[Path]:
    """``FOLDER/STEM_fl.png`` ... ``STEM_rr.png``."""
    return [Path(folder) / f"{stem}_{wheel}.png" for wheel in WHEELS]


def check_writable(paths: list[Path], force: bool) -> None:
    """Refuse to overwrite an existing file unless ``force``; the folder must exist."""
    for path in paths:
        if not path.parent.is_dir():
            raise ValueError(f"{path.parent}: no such folder for the figures (create it first)")
        if path.exists() and not force:
            raise ValueError(f"{path} exists: give --force to overwrite it")


def _save(figure, path: Path) -> None:
    """Write to a temporary file in the target folder, then rename over ``path``."""
    with replacing(path) as temporary:
        figure.savefig(temporary, dpi=110)


def plot_comparison(
    comparison: Comparison, signals: Signals, paths: list[Path], title: str = ""
) -> list[Path]:
    """One figure per wheel: reference and each method's estimate (top), their errors (bottom)."""
    t = signals.t
    for i, path in enumerate(paths):
        figure, (top, bottom) = plt.subplots(
            2, 1, figsize=(14, 7), sharex=True, gridspec_kw={"height_ratios": [2, 1.2]}
        )
        top.plot(t, signals.reference[:, i] / 1000.0, color="black", lw=1.4, label="reference")
        for result in comparison.results:
            load = result.estimate.loads[:, i]
            rmse = result.metrics.loc[WHEELS[i], "RMSE"]
            label = f"{result.info.name} (RMSE {rmse:.0f} N)"
            (line,) = top.plot(t, load / 1000.0, lw=0.9, label=label)
            bottom.plot(t, load - signals.reference[:, i], lw=0.8, color=line.get_color())
        for ax in (top, bottom):
            ax.axvspan(*comparison.window, color="0.9", zorder=0)
            ax.grid(alpha=0.3)
        top.set_ylabel("Fz [kN]")
        top.set_title(f"{WHEEL_NAMES[i]}{' — ' + title if title else ''}")
        top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        bottom.set_ylabel("error [N]")
        bottom.set_xlabel("t [s] (scored window shaded)")
        limit = np.nanpercentile(
            np.abs(np.concatenate([r.estimate.loads[:, i] - signals.reference[:, i]
                                   for r in comparison.results])), 99.5
        )  # fmt: skip
        bottom.set_ylim(-1.2 * limit - 1, 1.2 * limit + 1)
        figure.tight_layout()
        _save(figure, path)
        plt.close(figure)
    return paths


def write_csv(frame, path: Path) -> Path:
    """Write ``frame`` as CSV through a temporary file in the target folder, then rename."""
    with replacing(path) as temporary:
        frame.to_csv(temporary, index=False)
    return path
