"""The ``wheelload estimate --plot`` figure: :meth:`Estimate.plot` with the error panels.

One implementation (:mod:`wheelload.estimators.estimate_figure`): the loads, their ±2σ
band and the reference per wheel; under each wheel the error with the ±2σ band around
zero and the coverage (or the constraint residuals for a log without reference).
"""

from __future__ import annotations

from pathlib import Path

from wheelload.estimators import Estimate, Signals


def plot_estimate(estimate: Estimate, signals: Signals, path: str | Path, title: str = "") -> Path:
    """Save :meth:`Estimate.plot` (``errors=True``) of ``estimate`` on ``signals`` to ``path``."""
    path = Path(path)
    figure = estimate.plot(signals.reference, errors=True, title=title)
    figure.savefig(path, dpi=110)
    return path
