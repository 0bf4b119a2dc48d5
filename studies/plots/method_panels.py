"""What every figure comparing methods shares: one look per method, the reference on top,
the error distribution with limits from the data.

- :func:`method_styles`: a colour and a line style per method, no two methods with both
  the same (nine colours, then the next line style: unique up to 36 methods); black is
  the reference's alone.
- :func:`draw_against_reference`: one method's load under the reference (black, thicker,
  drawn last: the highest zorder).
- :func:`write_notes`: notes (e.g. identical methods shown once) at the figure's foot.
- :func:`draw_error_distribution`: a box per method of ``|estimate − reference|``, the axis
  set from the data (1.1 × the largest 99th percentile, said in the axis label), each
  method's 99th percentile marked and its maximum written where it leaves the axis.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

#: tab10 without its grey (the reference is black, the scored window light grey).
COLOURS = (
    "tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink",
    "tab:olive", "tab:cyan",
)  # fmt: skip
LINESTYLES = ("-", "--", "-.", ":")
#: A box's hatch per line style, so that a box tells the style apart too.
HATCHES = {"-": "", "--": "///", "-.": "\\\\\\", ":": "..."}
REFERENCE = {"color": "black", "lw": 1.6, "zorder": 3, "label": "reference"}
ESTIMATE_WIDTH = 1.0
ESTIMATE_ORDER = 2
#: The error axis ends at this multiple of the largest 99th percentile of ``|error|``.
HEADROOM = 1.1
PERCENTILE = 99.0
WHISKERS = (5.0, 95.0)


@dataclass(frozen=True)
class Style:
    """A method's colour and line style."""

    colour: str
    linestyle: str


def method_styles(names: Sequence[str]) -> dict[str, Style]:
    """A :class:`Style` per name, in order; no two share colour and line style."""
    most = len(COLOURS) * len(LINESTYLES)
    if len(names) > most:
        raise ValueError(f"{len(names)} methods in one figure: at most {most} have a style")
    return {
        name: Style(COLOURS[i % len(COLOURS)], LINESTYLES[i // len(COLOURS)])
        for i, name in enumerate(names)
    }


def draw_against_reference(ax, x, reference, load, style: Style, label: str) -> None:
    """``load`` in the method's style under ``reference`` (black, thicker, on top), in kN."""
    ax.plot(
        x, np.asarray(load) / 1000.0, color=style.colour, linestyle=style.linestyle,
        lw=ESTIMATE_WIDTH, zorder=ESTIMATE_ORDER, label=label,
    )  # fmt: skip
    ax.plot(x, np.asarray(reference) / 1000.0, **REFERENCE)
    ax.grid(alpha=0.3)


def error_limit(errors: Mapping[str, np.ndarray]) -> float:
    """The error axis' top [N]: :data:`HEADROOM` × the largest 99th percentile of ``|error|``."""
    top = max(float(np.percentile(np.abs(e), PERCENTILE)) for e in errors.values())
    return HEADROOM * top if top > 0 else 1.0


def draw_error_distribution(
    ax, errors: Mapping[str, np.ndarray], styles: Mapping[str, Style], where: str
) -> None:
    """A box of ``|error|`` [N] per method (25-75 %, whiskers 5-95 %), its 99th percentile (▼)
    and, where it leaves the axis, its maximum; ``where`` names the samples (title)."""
    names = list(errors)
    magnitudes = [np.abs(np.asarray(errors[name], float)) for name in names]
    positions = np.arange(1, len(names) + 1)
    boxes = ax.boxplot(
        magnitudes, positions=positions, whis=WHISKERS, showfliers=False, patch_artist=True,
        widths=0.6,
    )  # fmt: skip
    top = error_limit(errors)
    for k, name in enumerate(names):
        style = styles[name]
        boxes["boxes"][k].set(facecolor=style.colour, alpha=0.45, edgecolor=style.colour)
        boxes["boxes"][k].set(linestyle=style.linestyle, hatch=HATCHES[style.linestyle])
        boxes["medians"][k].set(color="black")
        p99 = float(np.percentile(magnitudes[k], PERCENTILE))
        ax.plot(positions[k], p99, "v", color=style.colour, markeredgecolor="black", ms=6)
        largest = float(magnitudes[k].max())
        if largest > top:
            ax.annotate(
                f"max {largest:.0f} N ↑", (positions[k], top), xytext=(0, -2),
                textcoords="offset points", ha="center", va="top", fontsize=7,
            )  # fmt: skip
    ax.set_xticks(positions, names, rotation=30, ha="right", fontsize=8)
    ax.set_xlim(0.4, len(names) + 0.6)
    ax.set_ylim(0.0, top)
    ax.set_ylabel(
        f"|error| [N]\n(axis to {HEADROOM:g} × the\nlargest {PERCENTILE:.0f}th percentile)"
    )
    ax.set_title(
        f"|estimate − reference|, {where}: box 25-75 %, whiskers "
        f"{WHISKERS[0]:.0f}-{WHISKERS[1]:.0f} %, ▼ {PERCENTILE:.0f}th percentile",
        fontsize=9,
    )
    ax.grid(axis="y", alpha=0.3)


def write_notes(figure, notes: Sequence[str], fontsize: float = 8.0) -> float:
    """Write ``notes`` at the foot of ``figure``, wrapped to its width; returns the share of
    its height they take (the bottom of ``tight_layout``'s ``rect``)."""
    width = int(figure.get_figwidth() * 125 / fontsize)  # characters a line holds
    lines = [line for note in notes for line in textwrap.wrap(f"note: {note}", width)]
    if not lines:
        return 0.0
    height = 1.5 * fontsize / 72.0 * len(lines) / figure.get_figheight()
    figure.text(0.01, 0.004, "\n".join(lines), fontsize=fontsize, va="bottom")
    return height + 0.01
