"""``wheelload bench discernment``: the KF with exact, loaded and wrong vehicle files on the
plant (:mod:`wheelload.studies.bench.discernment`), as the results page's tables."""

from __future__ import annotations

import argparse

from wheelload.studies.bench.discernment import PAYLOADS, rows
from wheelload.studies.drive.sensors import sensor_grade


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("discernment")
    parser.add_argument(
        "--grades",
        default="mti-1,consumer-mems",
        help="sensor grades (default mti-1,consumer-mems)",
    )
    parser.add_argument("--quick", action="store_true", help="iso-dlc and brake-in-turn only")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    grades = tuple(g.strip() for g in args.grades.split(",") if g.strip())
    if not grades:
        raise ValueError("--grades: give at least one sensor grade, e.g. mti-1")
    for grade in grades:
        sensor_grade(grade)  # an unknown grade is named before anything is simulated
    table = list(rows(grades, args.quick))
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
