"""Figures like the paper's: loads against reference (Fig. 5, 8) and metric bars (Fig. 6, 9, 10)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from wheelload.models.conventions import WHEELS
from wheelload.studies.metrics import COLUMNS  # noqa: E402

UNITS = {"RMSE": "RMSE [N]", "RMSE %": "RMSE [%]", "P95": "P95 [N]", "Max": "Max [N]"}


def _colours(count: int):
    return plt.get_cmap("tab20")(np.linspace(0.0, 1.0, max(count, 2)))


def loads_figure(t, reference, estimates: dict[str, np.ndarray], title: str):
    """Fig. 5: each wheel's estimates against the reference over the manoeuvre."""
    figure, axes = plt.subplots(2, 2, figsize=(13, 7.5), sharex=True)
    colours = _colours(len(estimates))
    for i, (ax, wheel) in enumerate(zip(axes.ravel(), WHEELS)):
        ax.plot(t, reference[:, i], color="black", lw=2.0, label="reference")
        for colour, (name, loads) in zip(colours, estimates.items()):
            ax.plot(t, loads[:, i], color=colour, lw=0.9, label=name)
        ax.set_title(wheel.upper())
        ax.set_ylabel("Fz [N]")
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("t [s]")
    axes[0, 1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.0))
    figure.suptitle(title)
    figure.tight_layout()
    return figure


def metric_bars(metrics: dict[str, pd.DataFrame], title: str):
    """Fig. 6/9/10: one panel per metric, wheels on the x axis, one bar per method."""
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
    figure.tight_layout()
    return figure


def front_left_panels(panels: list[tuple[str, np.ndarray, np.ndarray, dict]], xlabel: str):
    """Fig. 8: front-left load of selected methods against the reference, one panel per case."""
    figure, axes = plt.subplots(len(panels), 1, figsize=(12, 3.6 * len(panels)), squeeze=False)
    for ax, (title, x, reference, estimates) in zip(axes[:, 0], panels):
        ax.plot(x, reference[:, 0], color="black", lw=2.0, label="reference")
        for colour, (name, loads) in zip(_colours(len(estimates)), estimates.items()):
            ax.plot(x, loads[:, 0], color=colour, lw=1.0, label=name)
        ax.set_title(title)
        ax.set_ylabel("Fz FL [N]")
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    return figure


def close(figure) -> None:
    plt.close(figure)
