"""Tune the filter on logs and build the vehicle file's change set (``wheelload tune``'s logic).

Maximum likelihood of the filter's innovations for the constant and the input-dependent noise
densities (:mod:`wheelload.estimators.identification.tuning`); with reference loads ``fz_*``
in every log also the RMSE-minimising blend, a ±2σ coverage scale and the reported-σ model
fitted on the logs (:mod:`wheelload.estimators.identification.sigma_fit`). The change set's
keys are the tuning layout's vehicle-file keys (``estimators/kf/tuning.py: TUNING``), so the
values written follow the declaration, not a position.

Example
-------
>>> tuned = tune_file(vehicle, logs, iterations=400)
>>> text = tuned_text(path.read_text(), tuned, path.name)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators.identification.tuning import (
    TUNED_DENSITIES,
    TUNING,
    UPDATE_ROWS,
    noise_densities,
)
from wheelload.estimators.types import Signals
from wheelload.models import Vehicle
from wheelload.models.conventions import WHEELS
from wheelload.models.vehicle.description import SIGMA_KEYS
from wheelload.models.vehicle.file import add_values, prepend_comment

#: The comment written beside each fitted density (the first carries the fit's note).
DENSITY_COMMENTS = {
    "suspension_noise_density": "tuned (see above)",
    "constraint_noise_density": "tuned (see above)",
    "suspension_noise_rate_density": "tuned: R_s + this x v^2 / dt (models/measurement_noise.py)",
    "suspension_noise_hub_density": "tuned: R_s + this x (a_hub - az)^2 / dt",
    "constraint_noise_acceleration_density": "tuned: R_c + this x ((az - g)^2, ax^2, ay^2) / dt",
}
#: The line said when the logs carry no reference loads.
NO_REFERENCE = (
    "no reference loads fz_* in every log: cannot calibrate the reported sigma; "
    "the input file's sigma_* (or the defaults) are kept"
)


def reference_notes(logs: tuple[Signals, ...]) -> list[str]:
    """Lines said before the fit: the logs without reference loads (the RMSE tuning and the
    sigma calibration then do not run) and the wheels a partial reference leaves unscored."""
    notes = []
    without = [Path(s.source).name for s in logs if not s.reference_present.any()]
    if without and len(without) < len(logs):
        notes.append(
            f"no reference loads fz_* in {', '.join(without)}: the densities are fitted on "
            "every log, the RMSE tuning and the sigma calibration need references in every "
            "log and are left out (tune the logs with references on their own for them)"
        )
    for signals in logs:
        present = signals.reference_present
        if present.any() and not present.all():
            missing = " ".join(w.upper() for w, ok in zip(WHEELS, present) if not ok)
            shown = " ".join(w.upper() for w, ok in zip(WHEELS, present) if ok)
            notes.append(
                f"{Path(signals.source).name}: reference loads on {shown} only: "
                f"{missing} not scored (RMSE and sigma on the wheels with a reference)"
            )
    return notes


@dataclass(frozen=True, kw_only=True)
class TunedFile:
    """What ``tune`` writes: the tuned vehicle, the file's changes and what to tell."""

    vehicle: Vehicle  # densities, gate scale and (with references) the reported sigma
    changes: dict  # vehicle-file key -> (value, comment), in writing order
    note: str  # how the densities were chosen (the new file's header)
    sigma: object | None  # the reported sigma's calibration (sigma_fit), None without references
    report: tuple[str, ...]  # the fit's table, consistency and sigma lines
    warnings: tuple[str, ...]  # a tuning log's coverage out of band


def tune_file(vehicle: Vehicle, logs: tuple[Signals, ...], *, iterations: int) -> TunedFile:
    """Fit the densities on ``logs``, calibrate σ where every log has reference loads, and
    return the file's change set."""
    from wheelload.estimators.identification.sigma_fit import (  # SciPy: on use
        calibrate_sigma,
        coverage_warnings,
        with_sigma,
    )
    from wheelload.estimators.identification.tuning import FilterRuns, tune, tuned_vehicle

    references = all(signals.reference_present.any() for signals in logs)
    runs = FilterRuns(vehicle, logs)
    result = tune(runs, noise_densities(vehicle), references=references, iterations=iterations)
    report = fit_report(result, runs, references)
    new_vehicle = tuned_vehicle(vehicle, result)
    note = density_note(result, [Path(s.source).name for s in logs], references)
    changes = density_changes(result.tuned, note)
    changes[("filter", "gate_scale")] = (
        new_vehicle.filter.gate_scale,
        f"tuned: the gate's S x this (the densities were scaled x{result.scale:.3g})",
    )
    sigma, warnings = None, ()
    if references:
        sigma = calibrate_sigma(new_vehicle, runs.logs)
        new_vehicle = with_sigma(new_vehicle, sigma.coefficients)
        changes.update(sigma_changes(sigma.coefficients))
        report.append(
            f"reported sigma calibrated on the tuning logs: ±2σ coverage "
            f"{100 * sigma.coverage:.1f} %, r(σ, |error|) {sigma.correlation:.2f}"
        )
        warnings = tuple(
            coverage_warnings(
                "a tuning log's ±2σ coverage with sigma fitted on the other logs",
                zip((Path(s.source).name for s in runs.logs), sigma.held_out),
            )
        )
    else:
        report.append(NO_REFERENCE)
    return TunedFile(vehicle=new_vehicle, changes=changes, note=note, sigma=sigma,
                     report=tuple(report), warnings=warnings)  # fmt: skip


def density_changes(tuned: np.ndarray, note: str) -> dict:
    """The fitted densities (``TUNED_DENSITIES`` order) under their vehicle-file keys, a field
    of the tuning layout at a time (a vector field as a list)."""
    named = dict(zip(TUNED_DENSITIES, tuned, strict=True))
    changes = {}
    for field in TUNING.fields:
        if not set(field.parts) <= named.keys():
            continue
        values = [named[part] for part in field.parts]
        comment = DENSITY_COMMENTS.get(field.name, f"tuned: {note}")
        changes[field.file_key] = (values[0] if field.size == 1 else values, comment)
    return changes


def sigma_changes(coefficients: np.ndarray) -> dict:
    """The reported sigma's coefficients (``SIGMA_KEYS`` order) under their file keys."""
    comment = "tuned: reported sigma (estimators/kf/reported_std.py)"
    return {
        TUNING.field(key).file_key: (value, comment)
        for key, value in zip(SIGMA_KEYS, coefficients, strict=True)
    }


def density_note(result, log_names: list[str], references: bool) -> str:
    """How the written densities were chosen (the shape's source, the kept ratios, the
    coverage scale)."""
    from wheelload.estimators.identification.tuning import RATIOS

    logs = ", ".join(log_names)
    if result.shape_source == "input":
        note = f"the input file's densities (the likelihood shape of {logs} raised a log's RMSE)"
    else:
        note = f"maximum likelihood of the innovations of {logs}"
        if result.shape_source != "likelihood":
            note = f"{result.shape_source} of the input file's and the {note}"
        kept = [name for name in RATIOS if name not in result.agreed]
        if kept:
            note += (
                f", with the input file's ratio to suspension_noise_density of {', '.join(kept)}"
                " (the fits leaving one log out disagreed)"
            )
    if references:
        note += f", scaled x{result.scale:.3g} to 95 % ±2σ coverage with the guards on"
    return note


def fit_report(result, runs, references: bool) -> list[str]:
    """The fits side by side per density, the ratios taken, the blend's scores and the
    innovations' consistency before and after."""
    from wheelload.estimators.identification.tuning import (
        NIS_BAND,
        RATIO_AGREEMENT,
        RATIOS,
        RMSE_TOLERANCE,
    )

    columns = [
        ("input file", result.initial),
        ("max. likelihood", result.likelihood),
        *[(f"without log {k + 1}", fit) for k, fit in enumerate(result.folds)],
        ("agreed ratios", result.robust),
    ]
    if result.rmse is not None:
        columns += [
            ("min. RMSE", result.rmse),
            (f"written ({result.shape_source} x{result.scale:.3g})", result.tuned),
        ]
    lines = [f"{'density':>39}" + "".join(f"{label[:17]:>18}" for label, _ in columns)]
    for k, name in enumerate(TUNED_DENSITIES):
        lines.append(f"{name:>39}" + "".join(f"{values[k]:18.4g}" for _, values in columns))
    kept = [name for name in RATIOS if name not in result.agreed]
    lines.append(
        "ratios to suspension_noise_density taken from the likelihood (its fits on all logs"
        f" and leaving each out within {RATIO_AGREEMENT:g}x): {', '.join(result.agreed) or 'none'};"
        f" the input file's: {', '.join(kept) or 'none'}"
    )
    if result.scores:
        lines.append(
            "shape blend t (0 input, 1 likelihood): RMSE / input's per tuning log,"
            f" taken within {RMSE_TOLERANCE:g}x on every log"
        )
        for score in result.scores:
            held = ", ".join(f"{x:.3f}" for x in score.held_out) or "-"
            own = ", ".join(f"{x:.3f}" for x in score.in_sample)
            mark = "  <- written" if score.t == result.blend else ""
            lines.append(f"  t={score.t:<5g} left out: {held}; in sample: {own}{mark}")
    lo, hi = NIS_BAND
    lines.append(f"consistency on the tuning logs (NIS = y^2/S, 95 % band {lo:.3g}..{hi:.3g}):")
    for label, tuning, gate in (
        ("input", result.initial, 1.0),
        ("tuned", result.tuned, result.gate_factor),
    ):
        check = runs.consistency(tuning, gate)
        nis = ", ".join(
            f"{row} {m:.2f} ({100 * b:.0f} %)" if np.isfinite(m) else f"{row} n/a (never ran)"
            for row, m, b in zip(UPDATE_ROWS, check.nis_mean, check.nis_in_band)
        )
        extra = (
            f"; ±2σ coverage {100 * check.coverage:.1f} %, pooled RMSE {check.rmse:.1f} N"
            f", gated {100 * check.gated:.1f} % of rows"
            if references
            else ""
        )
        lines.append(f"  {label}: mean NIS (share in band) {nis}{extra}")
    return lines


def tuned_text(text: str, tuned: TunedFile, source_name: str) -> str:
    """The vehicle file ``text`` with the tuned values and a header saying how."""
    header = f"Filter tuned by `wheelload tune` from {source_name}: {tuned.note}.\n"
    return prepend_comment(add_values(text, tuned.changes), header)


def evaluation_table(
    vehicle: Vehicle, tuned: Vehicle, logs: tuple[Signals, ...]
) -> tuple[str, tuple[str, ...]]:
    """Per-log and pooled ±2σ coverage, RMSE and σ–``|error|`` correlation, input and tuned;
    and the warnings of a held-out log's coverage out of band."""
    if any(not signals.reference_present.any() for signals in logs):
        raise ValueError("--evaluate needs logs with reference loads fz_*")
    from wheelload.estimators.identification.sigma_fit import coverage_warnings
    from wheelload.estimators.identification.tuning import FilterRuns  # SciPy: on use

    lines = [
        "held-out logs: ±2σ coverage [%], pooled RMSE [N], correlation of σ and |error|,"
        " rows gated [%]; input file -> tuned",
        f"{'log':>28}{'cov in':>9}{'cov tuned':>11}{'RMSE in':>10}{'RMSE tuned':>12}"
        f"{'r in':>7}{'r tuned':>9}{'gated in':>10}{'gated tuned':>13}",
    ]
    groups = [(Path(s.source).name, (s,)) for s in logs] + [("pooled", logs)]
    tuned_coverage = []
    for name, group in groups:
        before = FilterRuns(vehicle, group, filter_sigma=False).consistency(
            noise_densities(vehicle)
        )
        after = FilterRuns(tuned, group, filter_sigma=False).consistency(noise_densities(tuned))
        lines.append(
            f"{name:>28}{100 * before.coverage:9.1f}{100 * after.coverage:11.1f}"
            f"{before.rmse:10.1f}{after.rmse:12.1f}"
            f"{before.sigma_error_correlation:7.2f}{after.sigma_error_correlation:9.2f}"
            f"{100 * before.gated:10.1f}{100 * after.gated:13.1f}"
        )
        tuned_coverage.append((name, after.coverage))
    what = "a held-out log's ±2σ coverage with the tuned file"
    return "\n".join(lines), tuple(coverage_warnings(what, tuned_coverage))
