"""``wheelload bench discernment``: the KF with exact, loaded and wrong vehicle files on the
plant (:mod:`wheelload.studies.bench.discernment`), as the results page's tables."""

from __future__ import annotations

import argparse
from pathlib import Path

from wheelload.models import load_vehicle
from wheelload.models.vehicle.description import SIGMA_KEYS
from wheelload.studies.bench.discernment import (
    NO_TRAVEL,
    NO_TRAVEL_KEYS,
    PAYLOADS,
    fit_no_travel,
    rows,
)
from wheelload.studies.drive.sensors import sensor_grade


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("discernment")
    parser.add_argument(
        "--grades",
        default="mti-1,consumer-mems",
        help="sensor grades (default mti-1,consumer-mems)",
    )
    parser.add_argument("--quick", action="store_true", help="iso-dlc and brake-in-turn only")
    parser.add_argument(
        "--vehicle",
        metavar="FILE",
        action="append",
        default=[],
        help="a further vehicle file the plant drives beside the bundled cars (repeat for more)",
    )
    parser.add_argument(
        "--sigma-only",
        action="store_true",
        help="the exact files only: the reported σ per car, scenario and grade, with every "
        f"sensor and in the case '{NO_TRAVEL}' (front references only)",
    )
    parser.add_argument(
        "--fit-no-travel",
        action="store_true",
        help="fit the reported σ's no-travel keys on every scenario without travel, as "
        f"logged and with ay {NO_TRAVEL.split('ay ')[1]} (the file keys, then each log's "
        "coverage)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    grades = tuple(g.strip() for g in args.grades.split(",") if g.strip())
    if not grades:
        raise ValueError("--grades: give at least one sensor grade, e.g. mti-1")
    for grade in grades:
        sensor_grade(grade)  # an unknown grade is named before anything is simulated
    vehicles = [Path(v) for v in args.vehicle]
    for path in vehicles:
        load_vehicle(path)  # a missing or implausible file is named before anything runs
    if args.fit_no_travel:
        fit, covered = fit_no_travel(grades, vehicles)
        for key, value in zip(SIGMA_KEYS, fit.coefficients, strict=True):
            if key in NO_TRAVEL_KEYS:
                print(f"{key} = {value:.4g}")
        for name, coverage in covered:
            print(f"{name}: ±2σ covers {100 * coverage:.1f} %")
        return 0
    every = not args.sigma_only
    table = list(rows(grades, args.quick, payloads=every, wrong=every, vehicles=vehicles,
                      no_travel=args.sigma_only))  # fmt: skip
    if args.sigma_only:
        for case in ("exact", NO_TRAVEL):
            _sigma_table(case, [r for r in table if r.case == case])
        return 0
    exact = {(r.car, r.scenario, r.grade): r for r in table if r.case == "exact"}
    print("| car | scenario | grade | file | RMSE [N] | x exact | isolated | named | "
          "mass [kg] | ±2σ covers | r(σ, |e|) | σ [N] |")  # fmt: skip
    print("|---" * 12 + "|")
    for r in table:
        base = exact[(r.car, r.scenario, r.grade)]
        print(
            f"| {r.car} | {r.scenario} | {r.grade} | {r.case} | {r.rmse:.1f} | "
            f"{r.rmse / base.rmse:.2f} | {r.isolated or '-'} | {r.named or '-'} | "
            f"{r.mass:.0f} | {100 * r.coverage:.1f} % | {r.correlation:.2f} | {r.sigma:.0f} |"
        )
    on_off = [
        exact[(r.car, r.scenario, r.grade)].rmse / r.rmse for r in table if r.case == "payload off"
    ]
    loaded = [
        r.rmse / exact[(r.car, r.scenario, r.grade)].rmse for r in table if r.case in PAYLOADS
    ]
    print(
        f"payload filter on / off, exact file: {min(on_off):.3f}-{max(on_off):.3f} x "
        f"({sum(x <= 1.02 for x in on_off)} of {len(on_off)} logs at most 1.02 x); payloads "
        f"against the exact file: {min(loaded):.2f}-{max(loaded):.2f} x "
        f"({sum(x <= 1.25 for x in loaded)} of {len(loaded)} at most 1.25 x)"
    )
    return 0


def _sigma_table(case: str, table) -> None:
    """The reported σ on the exact files (``case``): coverage and r per log, then the count
    within the targets (coverage 90-98 %, r >= 0.3)."""
    print(f"\n{case}:\n")
    print("| car | scenario | grade | RMSE [N] | ±2σ covers | r(σ, |e|) | σ [N] | "
          "mean |e| [N] | spread of |e| [N] |")  # fmt: skip
    print("|---" * 9 + "|")
    for r in table:
        print(
            f"| {r.car} | {r.scenario} | {r.grade} | {r.rmse:.1f} | "
            f"{100 * r.coverage:.1f} % | {r.correlation:.2f} | {r.sigma:.0f} | "
            f"{r.error_mean:.1f} | {r.error_spread:.1f} |"
        )
    least = sum(r.coverage >= 0.90 for r in table)
    covered = sum(0.90 <= r.coverage <= 0.98 for r in table)
    following = sum(r.correlation >= 0.3 for r in table)
    print(
        f"\n{case}: ±2σ covers at least 90 % on {least} of {len(table)} logs, 90-98 % on "
        f"{covered}; r >= 0.3 on {following}"
    )
