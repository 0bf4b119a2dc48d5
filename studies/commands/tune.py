"""``wheelload tune LOG ... --vehicle FILE --out NEW.toml``: fit the filter's noise densities.

Maximum likelihood of the filter's innovations (prediction-error method) for the
constant and the input-dependent densities (``models/measurement_noise.py``); the
ratios the leave-one-log-out fits do not agree on stay the input file's; with
reference loads ``fz_*`` in every log also the RMSE-minimising tuning, the blend
of input and likelihood shape no tuning log objects to, and a ±2σ coverage
calibration (``wheelload.estimators.identification.tuning``). The new file is a
copy of ``--vehicle`` with new ``[filter]`` densities and, with references,
``gate_scale = 1/c`` for densities scaled by c (the gate keeps its decisions, so
only σ is calibrated) and the reported-σ model's ``sigma_*`` fitted on the logs
(``wheelload.estimators.identification.sigma_fit``; without references the input
file's are kept)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from wheelload.estimators import TUNED_DENSITIES, UPDATE_ROWS, noise_densities
from wheelload.models.vehicle.description import SIGMA_KEYS
from wheelload.models.vehicle.file import (
    add_values,
    check_output_path,
    prepend_comment,
    write_vehicle_text,
)
from wheelload.studies.commands import CATALOG
from wheelload.studies.commands.options import CommandTraits, add_common_options, log_of, vehicle_of

#: The shared option groups this command takes (options.CommandTraits).
TRAITS = CommandTraits(log=True, vehicle=True, writes=True)


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "tune",
        help=CATALOG["tune"].summary,
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("logs", nargs="+", metavar="LOG", help="log files (.csv or .parquet)")
    parser.add_argument("--vehicle", required=True, help="vehicle file to start from (read only)")
    parser.add_argument("--out", required=True, help="new vehicle file (.toml)")
    parser.add_argument(
        "--evaluate",
        nargs="+",
        default=[],
        metavar="LOG",
        help="logs not used for tuning, with reference loads: print the before/after table",
    )
    parser.add_argument(
        "--iterations",
        type=int,
        default=400,
        help="Nelder-Mead iterations per fit (default 400; fewer for a quick look)",
    )
    add_common_options(parser, TRAITS)
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    # imported to run, not for --help (studies/commands/__init__.py)
    from wheelload.estimators.identification.sigma_fit import (
        calibrate_sigma,
        coverage_warnings,
        with_sigma,
    )
    from wheelload.estimators.identification.tuning import (
        NIS_BAND,
        RATIO_AGREEMENT,
        RATIOS,
        RMSE_TOLERANCE,
        FilterRuns,
        tune,
        tuned_vehicle,
    )

    vehicle_path = Path(args.vehicle)
    inputs = (vehicle_path, *map(Path, args.logs))
    out = check_output_path(args.out, inputs, args.force)
    vehicle = vehicle_of(vehicle_path, args)
    logs = tuple(log_of(path, args) for path in args.logs)
    references = all(signals.reference is not None for signals in logs)
    runs = FilterRuns(vehicle, logs)
    result = tune(runs, noise_densities(vehicle), references=references, iterations=args.iterations)
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
    print(f"{'density':>39}" + "".join(f"{label[:17]:>18}" for label, _ in columns))
    for k, name in enumerate(TUNED_DENSITIES):
        print(f"{name:>39}" + "".join(f"{values[k]:18.4g}" for _, values in columns))
    kept = [name for name in RATIOS if name not in result.agreed]
    print(
        "ratios to suspension_noise_density taken from the likelihood (its fits on all logs"
        f" and leaving each out within {RATIO_AGREEMENT:g}x): {', '.join(result.agreed) or 'none'};"
        f" the input file's: {', '.join(kept) or 'none'}"
    )
    if result.scores:
        print(
            "shape blend t (0 input, 1 likelihood): RMSE / input's per tuning log,"
            f" taken within {RMSE_TOLERANCE:g}x on every log"
        )
        for score in result.scores:
            held = ", ".join(f"{x:.3f}" for x in score.held_out) or "-"
            own = ", ".join(f"{x:.3f}" for x in score.in_sample)
            mark = "  <- written" if score.t == result.blend else ""
            print(f"  t={score.t:<5g} left out: {held}; in sample: {own}{mark}")
    lo, hi = NIS_BAND
    print(f"consistency on the tuning logs (NIS = y^2/S, 95 % band {lo:.3g}..{hi:.3g}):")
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
        print(f"  {label}: mean NIS (share in band) {nis}{extra}")
    tuned = result.tuned
    named = dict(zip(TUNED_DENSITIES, tuned, strict=True))
    new_vehicle = tuned_vehicle(vehicle, result)
    logs = ", ".join(Path(p).name for p in args.logs)
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
    changes = {
        ("filter", "process_noise_density"): (named["process_noise_density"], f"tuned: {note}"),
        ("filter", "suspension_noise_density"): (
            named["suspension_noise_density"],
            "tuned (see above)",
        ),
        ("filter", "constraint_noise_density"): (
            [named[f"constraint_noise_{r}"] for r in ("vertical", "pitch", "roll")],
            "tuned (see above)",
        ),
        ("filter", "suspension_noise_rate_density"): (
            named["suspension_noise_rate_density"],
            "tuned: R_s + this x v^2 / dt (models/measurement_noise.py)",
        ),
        ("filter", "suspension_noise_hub_density"): (
            named["suspension_noise_hub_density"],
            "tuned: R_s + this x (a_hub - az)^2 / dt",
        ),
        ("filter", "constraint_noise_acceleration_density"): (
            [named[f"constraint_noise_{r}_acceleration"] for r in ("vertical", "pitch", "roll")],
            "tuned: R_c + this x ((az - g)^2, ax^2, ay^2) / dt",
        ),
        ("filter", "gate_scale"): (
            new_vehicle.filter.gate_scale,
            f"tuned: the gate's S x this (the densities were scaled x{result.scale:.3g})",
        ),
    }
    if references:
        sigma = calibrate_sigma(new_vehicle, runs.logs)
        new_vehicle = with_sigma(new_vehicle, sigma.coefficients)
        changes.update(
            {
                ("filter", key): (value, "tuned: reported sigma (estimators/kf/reported_std.py)")
                for key, value in zip(SIGMA_KEYS, sigma.coefficients, strict=True)
            }
        )
        print(
            f"reported sigma calibrated on the tuning logs: ±2σ coverage "
            f"{100 * sigma.coverage:.1f} %, r(σ, |error|) {sigma.correlation:.2f}"
        )
        for warning in coverage_warnings(
            "a tuning log's ±2σ coverage with sigma fitted on the other logs",
            zip((Path(s.source).name for s in runs.logs), sigma.held_out),
        ):
            print(f"warning: {warning}", file=sys.stderr)
    else:
        print(
            "no reference loads fz_* in every log: cannot calibrate the reported sigma; "
            "the input file's sigma_* (or the defaults) are kept"
        )
    text = vehicle_path.read_text(encoding="utf-8")
    header = f"Filter tuned by `wheelload tune` from {vehicle_path.name}: {note}.\n"
    write_vehicle_text(
        prepend_comment(add_values(text, changes), header),
        out,
        inputs=inputs,
        force=args.force,
        allow_unusual=args.allow_unusual,
    )
    print(f"vehicle file written to {out}")
    if args.evaluate:
        print(evaluation_table(vehicle, new_vehicle, tuple(log_of(p, args) for p in args.evaluate)))
    return 0


def evaluation_table(vehicle, tuned, logs) -> str:
    """Per-log and pooled ±2σ coverage, RMSE and σ–``|error|`` correlation, input and tuned."""
    if any(signals.reference is None for signals in logs):
        raise ValueError("--evaluate needs logs with reference loads fz_*")
    from wheelload.estimators.identification.sigma_fit import coverage_warnings
    from wheelload.estimators.identification.tuning import FilterRuns  # SciPy: not for --help

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
    for warning in coverage_warnings(what, tuned_coverage):
        print(f"warning: {warning}", file=sys.stderr)
    return "\n".join(lines)
