"""Run registered methods on one log and score them with the paper's metrics (§IV-B, eq. 26-34).

Every method is reached through the registry (:func:`wheelload.estimators.registry.build`),
run over the whole log (``run``) and scored against the log's reference loads.
Wall time per sample is the median of ``repeat`` timed runs after one warm-up
run on a short slice (which compiles the method's C loop, cached on disk).

Example
-------
>>> result = compare_methods(signals, vehicle, ("kf", "C", "D"))
>>> print(format_table(result))
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from wheelload.estimators import DEFAULT_MODEL, SuspensionModel
from wheelload.estimators.protocol import MethodInfo
from wheelload.estimators.registry import build, method
from wheelload.estimators.result import Estimate
from wheelload.estimators.types import Signals
from wheelload.models import Vehicle
from wheelload.models.conventions import WHEELS
from wheelload.studies.identical import identical_groups, identity_notes, label
from wheelload.studies.metrics import COLUMNS, pooled_force_error, wheel_metrics

WARM_UP_SAMPLES = 50
UNITS = {"RMSE": "RMSE [N]", "RMSE %": "RMSE [%]", "P95": "P95 [N]", "Max": "MAX [N]"}


@dataclass(frozen=True, kw_only=True, eq=False)
class MethodResult:
    """One method's estimate on the log, its metric table and its time per sample [s]."""

    info: MethodInfo
    estimate: Estimate
    metrics: pd.DataFrame  # rows fl, fr, rl, rr, pooled; columns RMSE, RMSE %, P95, Max
    seconds_per_sample: tuple[float, ...]  # one per timed run
    # Tyre forces against the log's fx_*, fy_*: axis -> (RMSE fl..rr, pooled [N], % of RMS)
    forces: tuple[tuple[str, np.ndarray], ...] = ()


@dataclass(frozen=True, kw_only=True, eq=False)
class Comparison:
    """The methods' results on one log (scored over ``window`` [s])."""

    source: str
    samples: int
    window: tuple[float, float]
    results: tuple[MethodResult, ...]

    def loads(self) -> dict[str, np.ndarray]:
        """Each method's loads (n, 4) [N] over the whole log, by name."""
        return {r.info.name: r.estimate.loads for r in self.results}

    def identical(self) -> tuple[tuple[str, ...], ...]:
        """The methods grouped by identical loads (:func:`~wheelload.studies.identical.
        identical_groups`): tables and figures show one row or line a group."""
        return identical_groups(self.loads())

    def distinct(self) -> tuple[tuple[str, MethodResult], ...]:
        """``(label, result)`` of each group of identical methods, its first member's result
        (``projection-mp = projection-ls``)."""
        by_name = {r.info.name: r for r in self.results}
        return tuple((label(group), by_name[group[0]]) for group in self.identical())

    def notes(self) -> tuple[str, ...]:
        """Why each group of two or more methods is shown once."""
        return identity_notes(self.loads(), self.identical())


def parse_methods(text: str) -> tuple[str, ...]:
    """Comma-separated method names, each checked against the registry (canonical spelling)."""
    names = [part.strip() for part in text.split(",") if part.strip()]
    if not names:
        raise ValueError("--methods needs at least one method name, e.g. kf,C,D")
    canonical = tuple(method(name).name for name in names)
    duplicates = sorted({n for n in canonical if canonical.count(n) > 1})
    if duplicates:
        raise ValueError(f"--methods names {duplicates[0]!r} twice")
    return canonical


def evaluation_mask(t: np.ndarray, window: tuple[float, float]) -> np.ndarray:
    """Samples with ``start <= t <= end``; an empty window is an error."""
    start, end = window
    mask = (t >= start) & (t <= end)
    if not mask.any():
        raise ValueError(
            f"evaluation window {start:g}..{end:g} s holds no sample "
            f"(log spans {t[0]:g}..{t[-1]:g} s)"
        )
    return mask


def compare_methods(
    signals: Signals,
    vehicle: Vehicle,
    names: tuple[str, ...],
    *,
    window: tuple[float, float] | None = None,
    repeat: int = 3,
    suspension: SuspensionModel = DEFAULT_MODEL,
) -> Comparison:
    """Run and score each method on ``signals`` (which must carry reference loads).

    ``suspension``: the vehicle model of the family methods (default the KF's
    full model, so that the table compares estimators on one model;
    :class:`~wheelload.estimators.SuspensionModel`).
    """
    if signals.reference is None:
        raise ValueError(
            f"{signals.source}: no reference loads (columns fz_fl fz_fr fz_rl fz_rr): "
            "compare needs them; use `wheelload estimate` for a log without reference"
        )
    if repeat < 1:
        raise ValueError(f"repeat must be >= 1, got {repeat}")
    window = window or (float(signals.t[0]), float(signals.t[-1]))
    mask = evaluation_mask(signals.t, window)
    warm_up = signals.slice(0, min(WARM_UP_SAMPLES, len(signals)))
    results = []
    for name in names:
        info = method(name)
        estimator = build(name, vehicle, suspension)
        estimator.run(warm_up)
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            estimate = estimator.run(signals).named(info.name)
            times.append((time.perf_counter() - start) / len(signals))
        metrics = wheel_metrics(estimate.loads[mask], signals.reference[mask])
        results.append(
            MethodResult(
                info=info,
                estimate=estimate,
                metrics=metrics,
                seconds_per_sample=tuple(times),
                forces=force_errors(estimate, signals, mask),
            )  # fmt: skip
        )
    return Comparison(
        source=signals.source, samples=int(mask.sum()), window=window, results=tuple(results)
    )


def force_errors(estimate: Estimate, signals: Signals, mask: np.ndarray):
    """``(axis, row)`` for each tyre force the estimate has and the log references: the
    RMSE of each wheel and pooled [N], then the pooled RMSE as % of the reference RMS
    (:func:`~wheelload.studies.metrics.pooled_force_error`)."""
    rows = []
    for axis, values, reference in (("F_x", estimate.fx, signals.reference_fx),
                                    ("F_y", estimate.fy, signals.reference_fy)):  # fmt: skip
        if values is None or reference is None or not np.isfinite(reference[mask]).any():
            continue
        values, reference = values[mask], reference[mask]
        wheels = [pooled_force_error(values[:, i], reference[:, i])[0] for i in range(4)]
        rmse, rms = pooled_force_error(values, reference)
        share = 100.0 * rmse / rms if rms > 0 else float("nan")
        rows.append((axis, np.array([*wheels, rmse, share])))
    return tuple(rows)


def long_table(comparison: Comparison) -> pd.DataFrame:
    """One row per method and wheel (and pooled): metrics and median time per sample [µs]."""
    frames = []
    for result in comparison.results:
        frame = result.metrics.loc[:, list(COLUMNS)].copy()
        frame.insert(0, "method", result.info.name)
        frame.insert(1, "wheel", frame.index)
        frame["us_per_sample"] = 1e6 * float(np.median(result.seconds_per_sample))
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def format_table(comparison: Comparison) -> str:
    """The paper-style table (Tables II-IV): metric blocks, one row per method (identical
    methods in one row, with a note why); then the timings of every method."""
    distinct = comparison.distinct()
    width = max(6, *(len(name) for name, _ in distinct))
    header = f"{'Metric':<10}{'Method':<{width + 2}}" + "".join(
        f"{w:>10}" for w in ("FL", "FR", "RL", "RR", "pooled")
    )
    lines = [
        f"{comparison.source}: {comparison.samples} samples scored, "
        f"t = {comparison.window[0]:g}..{comparison.window[1]:g} s "
        "(Siegloff & Choi eq. 26-34)",
        header,
    ]
    for column in COLUMNS:
        for j, (name, result) in enumerate(distinct):
            values = result.metrics[column]
            digits = 2
            metric = UNITS[column] if j == 0 else ""
            lines.append(
                f"{metric:<10}{name:<{width + 2}}"
                + "".join(
                    f"{values[w]:>10.{digits}f}" if w in values.index else f"{'-':>10}"
                    for w in ("fl", "fr", "rl", "rr", "pooled")
                )
            )
    unscored = _unscored_wheels(comparison)
    if unscored:
        lines.append(
            f"note: not scored: {' '.join(w.upper() for w in unscored)} (no reference loads "
            f"fz_{'/'.join(unscored)} in the log); pooled is over the scored wheels"
        )
    lines.extend(f"note: {note}" for note in comparison.notes())
    lines.extend(_force_lines(comparison, width))
    lines.append("")
    lines.append(
        f"{'time per sample [µs]':<22}{'min':>10}{'median':>10}{'max':>10}   method: description"
    )
    for result in comparison.results:
        us = 1e6 * np.array(result.seconds_per_sample)
        lines.append(
            f"{result.info.name:<22}{us.min():>10.2f}{np.median(us):>10.2f}{us.max():>10.2f}"
            f"   {result.info.description}"
        )
    return "\n".join(lines)


def _unscored_wheels(comparison: Comparison) -> list[str]:
    """The wheels without a row in the metrics (no finite reference load)."""
    if not comparison.results:
        return []
    scored = comparison.results[0].metrics.index
    return [w for w in WHEELS if w not in scored]


def _force_lines(comparison: Comparison, width: int) -> list[str]:
    """The tyre forces' block of :func:`format_table` (methods that estimate them), F_x
    rows, then F_y rows."""
    rows = sorted(((axis, result.info.name, row) for result in comparison.results
                   for axis, row in result.forces), key=lambda r: r[0])  # fmt: skip
    if not rows:
        return []
    width = max(width, *(len(name) for _, name, _ in rows))
    columns = ("FL", "FR", "RL", "RR", "pooled", "% of RMS")
    header = f"{'Force':<10}{'Method':<{width + 2}}" + "".join(f"{c:>10}" for c in columns)
    lines = ["", "tyre forces against the log's fx_*, fy_* (tyre frame): RMSE [N]", header]
    for k, (axis, name, row) in enumerate(rows):
        shown = axis if k == 0 or rows[k - 1][0] != axis else ""
        lines.append(f"{shown:<10}{name:<{width + 2}}" + "".join(f"{v:>10.1f}" for v in row))
    return lines
