"""Figures of a method comparison, one per wheel: a panel per method against the reference,
then the distribution of every method's error.

Each method (identical ones once, :mod:`wheelload.studies.identical`) gets its own panel
and its own colour and line style (:mod:`~wheelload.studies.plots.method_panels`), the
reference on top of it; the bottom panel gives a box of ``|estimate − reference|`` per method
over the scored window, its axis set from the data (1.1 × the largest 99th percentile).

Example
-------
>>> comparison_figure(compare_methods(signals, vehicle, names), signals, 0).savefig("fl.png")
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

from wheelload.estimators.types import Signals
from wheelload.models.conventions import WHEELS
from wheelload.models.runtime.temporaries import replacing
from wheelload.studies.pipeline.comparison import Comparison, evaluation_mask
from wheelload.studies.plots.method_panels import (
    draw_against_reference,
    draw_error_distribution,
    method_styles,
    write_notes,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

WHEEL_NAMES = ("front left", "front right", "rear left", "rear right")
MOST_COLUMNS = 4


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


def comparison_figure(
    comparison: Comparison, signals: Signals, wheel: int, title: str = ""
) -> Figure:
    """Wheel ``wheel`` (0-3, FL..RR): a panel per method, its load under the reference; the
    error distribution of every method over the scored window; a note per identical group."""
    from matplotlib.figure import Figure

    distinct = comparison.distinct()
    styles = method_styles([name for name, _ in distinct])
    columns = min(MOST_COLUMNS, len(distinct))
    rows = math.ceil(len(distinct) / columns)
    notes = comparison.notes()
    figure = Figure(figsize=(15, 2.3 * rows + 4.2 + 0.3 * len(notes)))
    grid = figure.add_gridspec(rows + 1, columns, height_ratios=[1.0] * rows + [1.6])
    t, reference = signals.t, signals.reference[:, wheel]
    start, end = comparison.window
    first = None
    for k, (name, result) in enumerate(distinct):
        ax = figure.add_subplot(grid[k // columns, k % columns], sharex=first, sharey=first)
        first = first or ax
        ax.axvspan(start, end, color="0.93", zorder=0)
        load = result.estimate.loads[:, wheel]
        draw_against_reference(ax, t, reference, load, styles[name], name)
        rmse = result.metrics.loc[WHEELS[wheel], "RMSE"]
        ax.set_title(f"{name}: RMSE {rmse:.0f} N", fontsize=9)
        if k % columns == 0:
            ax.set_ylabel("Fz [kN]")
        if k + columns >= len(distinct):
            ax.set_xlabel("t [s] (scored window shaded)")
    first.legend(loc="best", fontsize=7)
    mask = evaluation_mask(t, comparison.window)
    errors = {
        name: result.estimate.loads[mask, wheel] - reference[mask] for name, result in distinct
    }
    where = f"t = {start:g}..{end:g} s ({int(mask.sum())} samples)"
    draw_error_distribution(figure.add_subplot(grid[rows, :]), errors, styles, where)
    figure.suptitle(f"{WHEEL_NAMES[wheel]}{' — ' + title if title else ''}")
    figure.tight_layout(rect=(0, write_notes(figure, notes), 1, 1))
    return figure


def plot_comparison(
    comparison: Comparison, signals: Signals, paths: list[Path], title: str = ""
) -> list[Path]:
    """Save :func:`comparison_figure` of each wheel with a reference load to its path of
    ``paths`` (FL, FR, RL, RR); the paths written (a wheel without a reference has none)."""
    scored = comparison.results[0].metrics.index if comparison.results else []
    written = []
    for i, path in enumerate(paths):
        if WHEELS[i] in scored:
            _save(comparison_figure(comparison, signals, i, title), path)
            written.append(path)
    return written


def write_csv(frame, path: Path) -> Path:
    """Write ``frame`` as CSV through a temporary file in the target folder, then rename."""
    with replacing(path) as temporary:
        frame.to_csv(temporary, index=False)
    return path
