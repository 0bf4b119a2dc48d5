"""Wall time of every scenario on the ground-truth plant: ``wheelload bench scenarios``.

Prints, per scenario, the simulated time, the plant build (code generation
and compilation) time, the wall time of the closed loop and the real-time
factor. Speed is measured here, never asserted in tests.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from wheelload.models.vehicle.file import example_vehicle_path
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.scenarios import SCENARIOS


def bench(names: Sequence[str], internal_rate: float, output_rate: float) -> list[dict]:
    """Run each scenario once with noise scale 1; return one record per scenario."""
    rows = []
    for name in names:
        result = run_scenario(
            name,
            example_vehicle_path(),
            options=Options(),
            noise=1.0,
            output_rate=output_rate,
            internal_rate=internal_rate,
        )
        info = result.metadata["summary"]
        rows.append(
            {
                "scenario": name,
                "simulated_s": info["duration_s"],
                "build_s": result.truth.build_time,
                "wall_s": result.truth.wall_time,
                "real_time_factor": info["duration_s"] / result.truth.wall_time,
            }
        )
        row = rows[-1]
        print(
            f"{name:20s} simulated {row['simulated_s']:8.1f} s  build {row['build_s']:5.2f} s  "
            f"wall {row['wall_s']:7.2f} s  x{row['real_time_factor']:7.1f} real time",
            flush=True,
        )
    return rows


def register_bench(subparsers) -> None:
    """``wheelload bench scenarios``."""
    parser = subparsers.add_parser("scenarios", description=__doc__)
    parser.add_argument("names", nargs="*", metavar="NAME", help="scenarios (default: all)")
    parser.add_argument(
        "--internal-rate",
        type=float,
        default=1000.0,
        help="plant integration rate [Hz], a multiple of --rate (default 1000)",
    )
    parser.add_argument("--rate", type=float, default=100.0, help="output rate [Hz] (default 100)")
    parser.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    names = args.names or sorted(SCENARIOS)
    unknown = [n for n in names if n not in SCENARIOS]
    if unknown:
        raise ValueError(f"unknown scenario '{unknown[0]}'; choose from {', '.join(SCENARIOS)}")
    bench(names, args.internal_rate, args.rate)
    return 0
