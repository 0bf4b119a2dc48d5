"""``wheelload estimate``: run the two-stage KF on a log, summarise, write and plot."""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

import numpy as np

from wheelload.estimators import Estimate, Signals, TwoStageKF, read_log
from wheelload.estimators.offsets import still_period_static_loads
from wheelload.estimators.result import StepFlag
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.metrics import wheel_metrics

WHEELS = ("FL", "FR", "RL", "RR")


def example_log_path() -> Path:
    """The bundled example log (sports car, see studies/data/README.md)."""
    return Path(str(resources.files("wheelload.studies") / "data" / "example_drive.csv"))


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "estimate", help="estimate the four wheel loads of a log with the two-stage KF"
    )
    parser.add_argument("log", nargs="?", help="log file (.csv or .parquet)")
    parser.add_argument("--vehicle", help="vehicle TOML file")
    parser.add_argument(
        "--example",
        action="store_true",
        help="use the bundled example log and vehicle (sports car)",
    )
    parser.add_argument("--out", help="write the estimates to this CSV file")
    parser.add_argument("--plot", help="save a figure of the estimates to this PNG file")
    parser.add_argument(
        "--still-period",
        type=float,
        metavar="SECONDS",
        help="zero the travel sensors over the first SECONDS of the log (vehicle at rest)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.example:
        log_path = Path(args.log) if args.log else example_log_path()
        vehicle_path = Path(args.vehicle) if args.vehicle else example_vehicle_path()
    else:
        if not args.log or not args.vehicle:
            raise ValueError("give a LOG and --vehicle FILE, or --example")
        log_path, vehicle_path = Path(args.log), Path(args.vehicle)
    vehicle = load_vehicle(vehicle_path)
    signals = read_log(log_path)
    static = (
        still_period_static_loads(signals, vehicle, args.still_period)
        if args.still_period
        else None
    )
    estimate = TwoStageKF(vehicle, static=static).run(signals)
    print(summary(estimate, signals, vehicle.name))
    if args.out:
        estimate.to_pandas().to_csv(args.out, index=False)
        print(f"estimates written to {args.out}")
    if args.plot:
        from wheelload.studies.plots import plot_estimate

        plot_estimate(estimate, signals, args.plot, title=f"{log_path.name} — {vehicle.name}")
        print(f"figure written to {args.plot}")
    return 0


def summary(estimate: Estimate, signals: Signals, vehicle_name: str) -> str:
    """A per-wheel text summary, with the paper's metrics where reference loads exist."""
    n = len(estimate)
    lines = [
        f"{signals.source}: {n} samples, {signals.t[-1] - signals.t[0]:.2f} s at "
        f"{signals.sample_rate:.0f} Hz, vehicle '{vehicle_name}'"
        + (
            ", suspension velocities derived (20 Hz differentiator)"
            if signals.velocities_derived
            else ""
        ),
        f"{'wheel':>6} {'mean [N]':>10} {'min [N]':>10} {'max [N]':>10} {'mean 1σ [N]':>12}",
    ]
    for i, wheel in enumerate(WHEELS):
        load = estimate.loads[:, i]
        lines.append(
            f"{wheel:>6} {load.mean():10.0f} {load.min():10.0f} {load.max():10.0f} "
            f"{estimate.std[:, i].mean():12.0f}"
        )
    updates = sum(StepFlag.update_flags()[:7]) | StepFlag.STEP_REJECTED
    flagged = int(np.count_nonzero(estimate.flags & updates))
    lines.append(f"samples with a skipped update (missing input): {flagged}")
    for flag in StepFlag.update_flags()[7:]:
        dropped = int(np.count_nonzero(estimate.flags & flag))
        if dropped:
            name = str(flag.name).lower().replace("_", " ")
            lines.append(f"samples with a model term dropped ({name}): {dropped}")
    if signals.reference is not None:
        table = wheel_metrics(estimate.loads, signals.reference)
        lines.append("error against the log's reference loads (Siegloff & Choi eq. 26-34):")
        lines.append(f"{'':>8}{'RMSE [N]':>10}{'RMSE [%]':>10}{'P95 [N]':>10}{'Max [N]':>10}")
        for name, row in table.iterrows():
            lines.append(
                f"{str(name).upper():>8}{row['RMSE']:10.1f}{row['RMSE %']:10.2f}"
                f"{row['P95']:10.1f}{row['Max']:10.1f}"
            )
    return "\n".join(lines)
