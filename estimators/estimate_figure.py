r"""The figure of one estimate: per wheel the loads with their ±2σ band, the reference on top.

The band is :math:`\hat F_z \pm 2\sigma` with σ the standard deviation the estimator
reports (``Estimate.std``: for the two-stage KF the reported-σ model of
:mod:`wheelload.estimators.kf.reported_std`, for the smoother the RTS covariance), drawn
as given, never refitted to the log. With reference loads each wheel's coverage
:math:`\frac{1}{n}\#\{k : |\hat F_{z,k} - F_{z,k}| < 2\sigma_k\}` (0.954 for an honest
Gaussian σ) is written in its panel, and the caption gives the pooled coverage, the ratio
of the median 2σ to the RMS error (2 for an honest Gaussian σ) and a verdict: σ
conservative (coverage above :data:`CONSERVATIVE`, the band wider than the errors, e.g. the
smoother's RTS covariance: coverage 100 %, 2σ ≈ 7 × the mean error on the bundled log),
honest, or optimistic (coverage below :data:`OPTIMISTIC`).

Matplotlib is imported inside :func:`estimate_figure` only (the estimators need it for
nothing else); the figure is a :class:`matplotlib.figure.Figure` outside pyplot, so no
global figure is left open and any backend can show or save it.

Example
-------
>>> figure = estimate_figure(t, loads, std, has_std=True, skipped=flags != 0, reference=ref)
>>> figure.savefig("loads.png")
"""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators.kernels import order_statistics
from wheelload.models.conventions import WHEELS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

WHEEL_NAMES = ("front left", "front right", "rear left", "rear right")
#: Share of a Gaussian within ±2σ: what an honest σ's coverage should be.
GAUSSIAN_COVERAGE = 0.9545
#: Pooled coverages above / below which σ is called conservative / optimistic.
CONSERVATIVE, OPTIMISTIC = 0.99, 0.90
ESTIMATE_COLOUR = "tab:blue"
#: Drawing order: band, estimate, reference (on top), skipped-update marks.
BAND_ORDER, ESTIMATE_ORDER, REFERENCE_ORDER, MARK_ORDER = 1, 2, 3, 4


def coverage(error: np.ndarray, std: np.ndarray) -> float:
    r"""Share of samples with :math:`|e| < 2\sigma` (NaN where no sample has both finite)."""
    error, std = np.asarray(error, float), np.asarray(std, float)
    finite = np.isfinite(error) & np.isfinite(std)
    if not finite.any():
        return float("nan")
    return float(np.mean(np.abs(error[finite]) < 2.0 * std[finite]))


def band_caption(
    has_std: bool,
    error: np.ndarray | None = None,
    std: np.ndarray | None = None,
    source: str = "",
) -> str:
    """The figure's caption: what the band is (``source``: where σ comes from) and, with the
    errors (n, 4) [N], the pooled coverage, the median 2σ over the RMS error, a verdict."""
    if not has_std:
        return "this method reports no standard deviation: no band is drawn"
    origin = source or "as the estimator reports it"
    text = f"band: estimate ± 2σ, σ {origin} (Estimate.std), not refitted to this log"
    if error is None or not np.isfinite(error).any():
        return text
    pooled = coverage(error, std)
    finite = np.isfinite(error) & np.isfinite(std)
    rms = float(np.sqrt(np.mean(error[finite] ** 2)))
    ratio = float(order_statistics.median(2.0 * std[finite])) / rms if rms > 0 else float("inf")
    return (
        f"{text}; coverage (share of samples with |estimate − reference| < 2σ) {pooled:.1%}, "
        f"median 2σ = {ratio:.1f} × the RMS error (an honest Gaussian σ: "
        f"{GAUSSIAN_COVERAGE:.1%}, 2.0 ×): {verdict(pooled)}"
    )


def verdict(pooled: float) -> str:
    """What a pooled coverage says of σ: conservative, honest or optimistic."""
    if pooled > CONSERVATIVE:
        return "σ conservative, the band wider than the errors"
    if pooled < OPTIMISTIC:
        return "σ optimistic, errors leave the band"
    return "σ about right"


def check_reference(reference: np.ndarray | None, samples: int) -> np.ndarray | None:
    """``reference`` as an (n, 4) float array, or None; a wrong shape names the fix."""
    if reference is None:
        return None
    reference = np.asarray(reference, float)
    if reference.shape != (samples, len(WHEELS)):
        raise ValueError(
            f"reference loads have shape {reference.shape}, the estimate {samples} samples "
            f"x {len(WHEELS)} wheels: give the log's reference (signals.reference) of the "
            "same samples"
        )
    return reference


def estimate_figure(
    t: np.ndarray,
    loads: np.ndarray,
    std: np.ndarray,
    *,
    has_std: bool,
    skipped: np.ndarray,
    reference: np.ndarray | None = None,
    residual: np.ndarray | None = None,
    errors: bool = False,
    title: str = "",
    std_source: str = "",
) -> Figure:
    """Four wheel panels (FL, FR, RL, RR): estimate, ±2σ band, reference on top.

    ``skipped``: samples whose update was skipped (marked ×). ``errors``: a panel under
    each wheel with the error against the reference and the ±2σ band around zero (with a
    reference), or the pitch and roll constraint residuals ``residual`` (without one).
    ``std_source``: where σ comes from, for the caption (default: as the estimator reports).
    """
    from matplotlib.figure import Figure

    t = np.asarray(t, float)
    reference = check_reference(reference, len(t))
    with_errors = errors and reference is not None
    with_residual = errors and reference is None and residual is not None
    figure = Figure(figsize=(12, 11 if with_errors else 9 if with_residual else 7.5))
    if with_errors:
        grid = figure.add_gridspec(4, 2, height_ratios=[2, 1, 2, 1])
        slots = [(2 * (i // 2), i % 2) for i in range(len(WHEELS))]
    else:
        ratios = [2, 2, 1.2] if with_residual else [1, 1]
        grid = figure.add_gridspec(len(ratios), 2, height_ratios=ratios)
        slots = [(i // 2, i % 2) for i in range(len(WHEELS))]
    first, bottoms = None, []
    for i, (row, column) in enumerate(slots):
        ax = figure.add_subplot(grid[row, column], sharex=first)
        first = first or ax
        held = reference is not None and np.isfinite(reference[:, i]).any()
        error = loads[:, i] - reference[:, i] if held else None  # NaN where no reference
        _draw_wheel(ax, t, loads[:, i], std[:, i], has_std, skipped, reference, i, error)
        if with_errors:
            below = figure.add_subplot(grid[row + 1, column], sharex=first)
            _draw_error(below, t, error, std[:, i], has_std)
            bottoms.append(below)
        elif not with_residual and row == 1:
            bottoms.append(ax)
    if with_residual:
        for j, name in enumerate(("pitch", "roll")):
            ax = figure.add_subplot(grid[2, j], sharex=first)
            ax.plot(t, residual[:, j + 1], lw=0.8, color="0.3")
            ax.set_title(f"{name} constraint residual b − A x")
            ax.set_ylabel("[N m]")
            ax.grid(alpha=0.3)
            bottoms.append(ax)
    for ax in bottoms:
        ax.set_xlabel("t [s]")
    figure.axes[0].legend(loc="best", fontsize=8)
    if title:
        figure.suptitle(title)
    error = None if reference is None else loads - reference
    caption = textwrap.fill(band_caption(has_std, error, std, std_source), 200)
    figure.text(0.01, 0.005, caption, fontsize=8, va="bottom")
    figure.tight_layout(rect=(0, 0.015 * (caption.count("\n") + 1) + 0.01, 1, 1))
    return figure


def _draw_wheel(ax, t, load, std, has_std, skipped, reference, i, error) -> None:
    """One wheel: band, estimate, reference on top, skipped updates; coverage in the title."""
    kilo = load / 1000.0
    if has_std:
        band = 2.0 * std / 1000.0
        ax.fill_between(
            t, kilo - band, kilo + band, color=ESTIMATE_COLOUR, alpha=0.25, lw=0,
            label="estimate ± 2σ", zorder=BAND_ORDER,
        )  # fmt: skip
    ax.plot(t, kilo, color=ESTIMATE_COLOUR, lw=1.0, label="estimate", zorder=ESTIMATE_ORDER)
    if reference is not None:
        ax.plot(
            t, reference[:, i] / 1000.0, color="black", lw=1.6, label="reference",
            zorder=REFERENCE_ORDER,
        )  # fmt: skip
    marked = np.asarray(skipped, bool)
    if marked.any():
        ax.plot(
            t[marked], kilo[marked], "x", color="tab:red", ms=3, label="update skipped",
            zorder=MARK_ORDER,
        )  # fmt: skip
    heading = WHEEL_NAMES[i]
    if error is not None:
        rms = np.sqrt(np.nanmean(error**2))
        heading += f": RMS error {rms:.0f} N"
        if has_std:
            heading += f", |error| < 2σ in {coverage(error, std):.1%}"
    ax.set_title(heading)
    ax.set_ylabel("Fz [kN]")
    ax.grid(alpha=0.3)


def _draw_error(ax, t, error, std, has_std) -> None:
    """The error against the reference [N], with the ±2σ band around zero."""
    ax.set_ylabel("error [N]")
    ax.grid(alpha=0.3)
    if error is None:
        ax.text(0.5, 0.5, "no reference loads for this wheel", transform=ax.transAxes,
                ha="center", va="center", color="0.4")  # fmt: skip
        return
    if has_std:
        ax.fill_between(
            t, -2.0 * std, 2.0 * std, color=ESTIMATE_COLOUR, alpha=0.25, lw=0, label="± 2σ",
            zorder=BAND_ORDER,
        )  # fmt: skip
    ax.plot(t, error, color="black", lw=0.8, label="estimate − reference", zorder=ESTIMATE_ORDER)
    ax.axhline(0.0, color="0.5", lw=0.6, zorder=0)
    ax.legend(loc="upper right", fontsize=7, ncol=2)
