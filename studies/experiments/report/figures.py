"""Figures like the paper's: loads against reference (Fig. 5, 8) and metric bars (Fig. 6, 9, 10).

Each method has its own colour and line style and the reference is drawn on top
(:mod:`wheelload.studies.plots.method_panels`); Fig. 5 is small multiples, a row per method.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from wheelload.models.conventions import WHEELS
from wheelload.studies.metrics import COLUMNS  # noqa: E402
from wheelload.studies.plots.method_panels import (  # noqa: E402
    ESTIMATE_ORDER,
    REFERENCE,
    draw_against_reference,
    method_styles,
    write_notes,
)

UNITS = {"RMSE": "RMSE [N]", "RMSE %": "RMSE [%]", "P95": "P95 [N]", "Max": "Max [N]"}


def _colours(count: int):
    return plt.get_cmap("tab20")(np.linspace(0.0, 1.0, max(count, 2)))


def loads_figure(t, reference, estimates: dict[str, np.ndarray], title: str, notes=()):
    """Fig. 5 as small multiples: a row per method, a column per wheel, each panel the
    method's load (its own colour and line style) under the reference (black, on top)."""
    styles = method_styles(list(estimates))
    rows = len(estimates)
    figure, axes = plt.subplots(
        rows, len(WHEELS), figsize=(14, 1.15 * rows + 1.6 + 0.3 * len(notes)),
        sharex=True, sharey="col", squeeze=False,
    )  # fmt: skip
    for r, (name, loads) in enumerate(estimates.items()):
        for i, wheel in enumerate(WHEELS):
            ax = axes[r, i]
            draw_against_reference(ax, t, reference[:, i], loads[:, i], styles[name], name)
            ax.tick_params(labelsize=7)
            if r == 0:
                ax.set_title(f"{wheel.upper()}: Fz [kN]", fontsize=9)
        wrapped = name.replace(" = ", " =\n")  # projection-mp =\nprojection-ls
        axes[r, 0].set_ylabel(wrapped, fontsize=8, rotation=0, ha="right", va="center")
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    figure.suptitle(f"{title}: each method (row) under the reference (black)")
    figure.tight_layout(rect=(0, write_notes(figure, notes, 7), 1, 0.985), h_pad=0.2)
    return figure


def metric_bars(metrics: dict[str, pd.DataFrame], title: str, notes=()):
    """Fig. 6/9/10: one panel per metric, wheels on the x axis, one bar per method; a
    ``note`` per group of identical methods shown once."""
    figure, axes = plt.subplots(2, 2, figsize=(13, 7.5))
    names = list(metrics)
    colours = _colours(len(names))
    width = 0.8 / len(names)
    x = np.arange(len(WHEELS))
    for ax, column in zip(axes.ravel(), COLUMNS):
        for j, (colour, name) in enumerate(zip(colours, names)):
            values = [metrics[name].loc[w, column] for w in WHEELS]
            ax.bar(x + (j - len(names) / 2 + 0.5) * width, values, width, color=colour, label=name)
        ax.set_xticks(x, [w.upper() for w in WHEELS])
        ax.set_ylabel(UNITS[column])
        ax.grid(axis="y", alpha=0.3)
    axes[0, 1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.0))
    figure.suptitle(title)
    figure.tight_layout(rect=(0, write_notes(figure, notes, 7), 1, 1))
    return figure


def front_left_panels(panels: list[tuple[str, np.ndarray, np.ndarray, dict]], xlabel: str):
    """Fig. 8: front-left load of selected methods against the reference, one panel per case."""
    figure, axes = plt.subplots(len(panels), 1, figsize=(12, 3.6 * len(panels)), squeeze=False)
    for ax, (title, x, reference, estimates) in zip(axes[:, 0], panels):
        styles = method_styles(list(estimates))
        for name, loads in estimates.items():
            ax.plot(
                x, loads[:, 0], color=styles[name].colour, linestyle=styles[name].linestyle,
                lw=1.0, zorder=ESTIMATE_ORDER, label=name,
            )  # fmt: skip
        ax.plot(x, reference[:, 0], **{**REFERENCE, "lw": 2.0})
        ax.set_title(title)
        ax.set_ylabel("Fz FL [N]")
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    return figure


def close(figure) -> None:
    plt.close(figure)
