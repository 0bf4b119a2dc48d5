"""What ``wheelload estimate`` tells about one log: the text summary and the summary-table row.

Both are built from a log's :class:`LogHeader` (read whole or scanned for the
lean path) and the figures of its estimates (:class:`EstimateDigest`); the
summary's metrics are Siegloff & Choi eq. 26-34.

Example
-------
>>> print(summary(estimate, signals, vehicle.name))
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from wheelload.estimators import Estimate, Signals, StepFlag
from wheelload.estimators.logs.own_clocks import scored_reference
from wheelload.models import WHEELS
from wheelload.studies.metrics import pooled_force_error, wheel_metrics
from wheelload.studies.pipeline.estimate_digest import EstimateDigest


class ScannedLog(Protocol):
    """What a log read whole (:class:`Signals`) and a log scanned for the lean path
    (:class:`~wheelload.estimators.LogStream`) both tell of themselves."""

    source: str
    t: np.ndarray
    velocities_derived: bool
    az_assumed: bool

    @property
    def sample_rate(self) -> float: ...

    def mode(self) -> str: ...


def digest_of(estimate: Estimate, signals: Signals) -> EstimateDigest:
    """The summary figures of a whole-log estimate (one chunk)."""
    reference = scored_reference(signals)
    wheels = None if reference is None else np.any(np.isfinite(reference), axis=0)
    digest = EstimateDigest(
        samples=len(estimate), reference_wheels=wheels, has_std=estimate.has_std
    )
    digest.add(estimate.loads, estimate.std, estimate.flags, reference)
    digest.model_errors = estimate.model_errors
    if estimate.mass_properties is not None:
        digest.add_mass_properties(
            np.hstack([estimate.mass_properties, estimate.mass_properties_std])
        )
    return digest


def row_use(estimate: Estimate) -> str:
    """Share of samples in which each suspension row and the roll-split row were used.

    A suspension row needs both travel sensors of its axle (the anti-roll bar
    couples them); the roll-split row is used when no suspension row is.
    """
    digest = EstimateDigest(samples=len(estimate), reference_wheels=None)
    digest.add(estimate.loads, estimate.std, estimate.flags)
    return _row_use(digest)


def _row_use(digest: EstimateDigest) -> str:
    shares = ", ".join(
        f"{w.upper()} {100 * (1 - s / digest.n):.0f} %"
        for w, s in zip(WHEELS, digest.suspension_skipped)
    )
    split = 100 * digest.split / digest.n
    return f"suspension rows used: {shares}; roll-split row used: {split:.0f} %"


def guard_lines(estimate: Estimate) -> list[str]:
    """Summary lines of the guards: gated and implausible samples, isolated sensor faults."""
    digest = EstimateDigest(samples=len(estimate), reference_wheels=None)
    digest.add(estimate.loads, estimate.std, estimate.flags)
    return _guard_lines(digest, estimate.sensor_faults)


def _guard_lines(digest: EstimateDigest, faults, assumed: tuple[str, ...] = ()) -> list[str]:
    """Guard lines; a fault on an ``assumed`` channel (the log lacks it) is the assumption
    failing, not a sensor's fault, and is said so."""
    lines = []
    named = ", ".join(f"{flag.name.lower()} {n}" for flag, n in digest.guards.items() if n)
    if named:
        lines.append(f"samples flagged by the guards: {named}")
    for fault in faults:
        if fault.channel in assumed:
            lines.append(
                f"the assumed {fault.channel} (not in the log) does not hold from "
                f"{fault.start:.2f} s to {fault.end:.2f} s (test statistic "
                f"{fault.statistic:.1f}); it was left out of the updates: log {fault.channel}"
            )
            continue
        lines.append(
            f"sensor fault: {fault.channel} from {fault.start:.2f} s to {fault.end:.2f} s "
            f"(test statistic {fault.statistic:.1f}); the channel was left out of the updates"
        )
    return lines


def summary(estimate: Estimate, signals: Signals, vehicle_name: str) -> str:
    """A per-wheel text summary, with the paper's metrics where reference loads exist.

    A metrics problem is reported in the text, never raised: the estimates
    stand on their own.
    """
    header = LogHeader.of(signals, has_reference=signals.reference is not None)
    text = summary_text(header, digest_of(estimate, signals), estimate.sensor_faults, vehicle_name)
    return "\n".join([text, *tyre_force_lines(estimate, signals)])


def tyre_force_lines(estimate: Estimate, signals: Signals) -> list[str]:
    """The pooled error of the tyre forces an estimate has, where the log has their
    reference (``fx_*``, ``fy_*``): RMSE and % of the reference RMS
    (:func:`~wheelload.studies.metrics.pooled_force_error`)."""
    lines = []
    for axis, values, reference in (("F_x", estimate.fx, signals.reference_fx),
                                    ("F_y", estimate.fy, signals.reference_fy)):  # fmt: skip
        if values is None or reference is None or not np.isfinite(reference).any():
            continue
        rmse, rms = pooled_force_error(values, reference)
        share = f"{100.0 * rmse / rms:.1f} % of" if rms > 0 else "against"
        lines.append(f"tyre force {axis} against the log's reference: pooled RMSE {rmse:.0f} N "
                     f"({share} its RMS {rms:.0f} N)")  # fmt: skip
    return lines


@dataclass(frozen=True, kw_only=True)
class LogHeader:
    """What the summary says of the log itself."""

    source: str
    samples: int
    duration: float
    sample_rate: float
    velocities_derived: bool
    mode: str
    has_reference: bool
    assumed: tuple[str, ...] = ()  # channels the log lacks, taken as assumed values

    @classmethod
    def of(cls, log: ScannedLog, *, has_reference: bool) -> LogHeader:
        """The header of a log read whole or scanned for the lean path (:class:`ScannedLog`)."""
        return cls(
            source=log.source,
            samples=len(log.t),
            duration=float(log.t[-1] - log.t[0]),
            sample_rate=log.sample_rate,
            velocities_derived=log.velocities_derived,
            mode=log.mode(),
            has_reference=has_reference,
            assumed=("az",) if log.az_assumed else (),
        )


def summary_text(header: LogHeader, digest: EstimateDigest, faults, vehicle_name: str) -> str:
    """The text of :func:`summary` from a log's header and its :class:`EstimateDigest`."""
    lines = [
        f"{header.source}: {header.samples} samples, {header.duration:.2f} s at "
        f"{header.sample_rate:.0f} Hz, vehicle '{vehicle_name}'"
        + (
            ", suspension velocities derived (20 Hz differentiator)"
            if header.velocities_derived
            else ""
        ),
        f"{'wheel':>6} {'mean [N]':>10} {'min [N]':>10} {'max [N]':>10} {'mean 1σ [N]':>12}",
    ]
    means, stds = digest.means(), digest.mean_std()
    for i, wheel in enumerate(WHEELS):
        std = f"{stds[i]:12.0f}" if digest.has_std else f"{'n/a':>12}"
        lines.append(
            f"{wheel.upper():>6} {means[i]:10.0f} {digest.load_min[i]:10.0f} "
            f"{digest.load_max[i]:10.0f} {std}"
        )
    lines.append(f"sensor set: {header.mode}")
    if digest.mass_properties is not None:
        lines.append(mass_properties_line(digest.mass_properties))
    lines.extend(finding.message() for finding in digest.model_errors)
    lines.append(_row_use(digest))
    lines.append(f"samples with a skipped update (missing or guarded input): {digest.skipped}")
    if digest.assumed:
        lines.append(f"samples with an assumed input (status bits 20-22): {digest.assumed}")
    lines.extend(_guard_lines(digest, faults, header.assumed))
    for flag, dropped in digest.dropped.items():
        if dropped:
            name = str(flag.name).lower().replace("_", " ")
            lines.append(f"samples with a model term dropped ({name}): {dropped}")
    if header.has_reference:
        try:
            names, rows = digest.metric_rows(header.source)
        except ValueError as error:
            lines.append(f"no error metrics: {error}")
            return "\n".join(lines)
        lines.append("error against the log's reference loads (Siegloff & Choi eq. 26-34):")
        lines.append(f"{'':>8}{'RMSE [N]':>10}{'RMSE [%]':>10}{'P95 [N]':>10}{'Max [N]':>10}")
        for name, (rmse, rmse_percent, p95, peak) in zip(names, rows, strict=True):
            lines.append(
                f"{name.upper():>8}{rmse:10.1f}{rmse_percent:10.2f}{p95:10.1f}{peak:10.1f}"
            )
    return "\n".join(lines)


def mass_properties_line(values: np.ndarray) -> str:
    """The online mass and CG at the end of the log (values then std, ``MASS_PROPERTIES``);
    a property with std 0 is not estimated and is said to be assumed (the file's, or the
    payload at the CG's height), never ± 0."""
    (mass, x, y, height), spread = values[:4], values[4:]
    if not np.any(spread > 0):
        return (
            f"mass and CG as the file gives them (not estimated online): {mass:.0f} kg, "
            f"CG {height:.3f} m high"
        )

    def shown(value: float, spread: float, form: str, unit: str) -> str:
        return f"{value:{form}} ± {spread:.3f} {unit}" if spread > 0 else f"{value:{form}} {unit}"

    height_text = (
        f"{height:.3f} ± {spread[3]:.3f} m high"
        if spread[3] > 0
        else f"{height:.3f} m high (assumed: the payload at the CG's height)"
    )
    return (
        f"mass and CG estimated online (end of log): {mass:.0f} ± {spread[0]:.0f} kg; CG "
        f"{shown(x, spread[1], '+.3f', 'm')} ahead and {shown(y, spread[2], '+.3f', 'm')} "
        f"left of the file's, {height_text}"
    )


@dataclass(frozen=True, kw_only=True)
class LoadFigures:
    """The summary table's figures of a log's estimates (loads in N)."""

    mean: np.ndarray  # (4,) mean load per wheel
    mean_std: np.ndarray  # (4,) mean standard deviation per wheel
    skipped: int  # samples with a skipped update
    negative: int  # samples with a negative load
    minimum: float  # smallest load of any wheel
    rmse_pooled: float  # pooled RMSE against the reference loads; NaN: no sample to score

    @classmethod
    def of_estimate(cls, estimate: Estimate, signals: Signals, source: str) -> LoadFigures:
        """The figures of a whole-log estimate, computed on its arrays."""
        reference = scored_reference(signals)
        rmse = np.nan
        if reference is not None and np.isfinite(reference).any():
            rmse = _pooled_rmse(lambda: wheel_metrics(estimate.loads, reference, source=source))
        return cls(
            mean=np.array([float(estimate.loads[:, i].mean()) for i in range(4)]),
            mean_std=np.array([float(estimate.std[:, i].mean()) for i in range(4)]),
            skipped=int(np.count_nonzero(estimate.flags & StepFlag.skipped_mask())),
            negative=int((estimate.loads < 0).any(axis=1).sum()),
            minimum=float(estimate.loads.min()),
            rmse_pooled=rmse,
        )

    @classmethod
    def of_digest(cls, digest: EstimateDigest, source: str) -> LoadFigures:
        """The figures of estimates gathered chunk by chunk (the lean path); once only."""
        return cls(
            mean=digest.means(),
            mean_std=digest.mean_std(),
            skipped=digest.skipped,
            negative=digest.negative_samples,
            minimum=float(digest.load_min.min()),
            rmse_pooled=_pooled_rmse(lambda: digest.metrics(source)),
        )


def _pooled_rmse(metrics) -> float:
    """The pooled RMSE of a metrics table (``metrics()``), NaN where there is nothing to score."""
    try:
        return float(metrics().loc["pooled", "RMSE"])
    except ValueError:
        return np.nan  # no sample to score


#: Separates a log's messages in the summary table's ``messages`` cell.
MESSAGE_SEPARATOR = " | "


def summary_row(
    log: str,
    header: LogHeader,
    figures: LoadFigures,
    warnings: tuple[str, ...],
    notes: tuple[str, ...] = (),
) -> dict:
    """One row of the summary table of many logs: the log, its estimates' figures, the
    number of warnings, the log's notes and warnings (wiring and plausibility checks among
    them) joined by :data:`MESSAGE_SEPARATOR`, and an empty error."""
    row = {
        "log": log,
        "samples": header.samples,
        "duration_s": header.duration,
        "rate_hz": header.sample_rate,
        "mode": header.mode,
    }
    for i, wheel in enumerate(WHEELS):
        row[f"mean_fz_{wheel}"] = float(figures.mean[i])
    for i, wheel in enumerate(WHEELS):
        row[f"mean_std_{wheel}"] = float(figures.mean_std[i])
    row["skipped_samples"] = figures.skipped
    row["negative_samples"] = figures.negative
    row["min_fz"] = figures.minimum
    row["rmse_pooled"] = figures.rmse_pooled
    row["warnings"] = len(warnings)
    row["messages"] = MESSAGE_SEPARATOR.join((*notes, *warnings))
    row["error"] = ""
    return row
