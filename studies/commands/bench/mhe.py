"""``wheelload bench mhe``: the MHE's time per sample beside the KF's.

In the same run, from Python and (when a C compiler is found) from the
generated C. The embedded MHE's C is written by ``wheelload codegen --estimator mhe``.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from wheelload.estimators import Constraint, MheSettings
from wheelload.estimators.registry import build
from wheelload.models import load_vehicle
from wheelload.studies.commands.options import add_vehicle_file_options, vehicle_file
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log
from wheelload.studies.experiments.mhe_vs_kf import robust_candidates, step_times


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench mhe``."""
    bench = subparsers.add_parser("mhe")
    bench.add_argument("--samples", type=int, default=3000, help="samples per run (default 3000)")
    bench.add_argument(
        "--horizons", type=int, nargs="+", default=[10, 20], help="window lengths N (default 10 20)"
    )
    bench.add_argument("--no-c", action="store_true", help="skip the generated C")
    bench.add_argument(
        "--repeats",
        type=int,
        default=3,
        help="runs of each generated C and of the window against bare OSQP (default 3)",
    )
    add_vehicle_file_options(bench)
    bench.set_defaults(handler=run_bench)


def run_bench(args: argparse.Namespace) -> int:
    vehicle_path = vehicle_file(args)
    vehicle = load_vehicle(vehicle_path, allow_unusual=args.allow_unusual)
    duration = args.samples / 100.0
    signals = synthetic_log(vehicle, slalom(duration=duration), noise=SensorNoise(
        acceleration=0.05, travel=0.0003), spring_error=0.08)  # fmt: skip
    kf = build("kf", vehicle)
    kf.run(signals.slice(0, 10))
    start = time.perf_counter()
    kf.run(signals)
    kf_run = (time.perf_counter() - start) / len(signals) * 1e6
    kf_step = np.median(step_times(kf, signals, len(signals))) * 1e6
    print(f"{len(signals)} samples at 100 Hz (synthetic slalom)")
    print(f"{'estimator':38s} {'median us':>10s} {'p99 us':>10s} {'x KF step':>10s}")
    print(f"{'KF step (Python, CasADi call)':38s} {kf_step:10.1f} {'':>10s} {1.0:10.2f}")
    print(f"{'KF run (compiled loop, amortised)':38s} {kf_run:10.2f}")
    _bench_window(vehicle, signals, args.horizons, args.repeats)
    _bench_assembly(vehicle, signals.slice(0, min(len(signals), 500)), args.horizons, args.repeats)
    c_available = not args.no_c and shutil.which("gcc") is not None
    for horizon in args.horizons:
        for constraint in Constraint:
            for bounded in (False, True):
                settings = MheSettings(horizon=horizon, constraint=constraint, bounded=bounded)
                estimate = build("mhe", vehicle, settings=settings).run(signals)
                times = estimate.solve_time * 1e6
                median = float(np.median(times))
                print(f"{settings.label() + ' Python':38s} {median:10.1f} "
                      f"{np.percentile(times, 99):10.1f} {median / kf_step:10.2f}")  # fmt: skip
                if c_available:
                    _bench_c(vehicle, vehicle_path, settings, signals, kf_step, args.repeats)
        for candidate in robust_candidates(horizon):
            if candidate.settings is None or not (
                candidate.settings.extended or candidate.settings.lag
            ):
                continue
            estimate = build("mhe", vehicle, settings=candidate.settings).run(signals)
            times = estimate.solve_time * 1e6
            median = float(np.median(times))
            print(f"{candidate.name + ' Python':38s} {median:10.1f} "
                  f"{np.percentile(times, 99):10.1f} {median / kf_step:10.2f}")  # fmt: skip
            if c_available:
                _bench_c(vehicle, vehicle_path, candidate.settings, signals, kf_step,
                         args.repeats, name=candidate.name)  # fmt: skip
    kf.smooth(signals.slice(0, 10))  # builds the compiled backward pass once
    smooth = []
    for _ in range(5):
        start = time.perf_counter()
        kf.smooth(signals)
        smooth.append((time.perf_counter() - start) / len(signals) * 1e6)
    print(f"{'KF + RTS smoother (compiled, amortised)':38s} {np.median(smooth):10.2f} "
          f"{'':>10s} (min {min(smooth):.2f}, max {max(smooth):.2f})")  # fmt: skip
    return 0


def _bench_window(vehicle, signals, horizons: list[int], repeats: int) -> None:
    """The window from Python against a bare OSQP solve of the same QPs (min/median/max)."""
    from wheelload.studies.bench.mhe import window_against_bare_osqp

    if repeats < 1:
        raise ValueError(f"--repeats must be >= 1, got {repeats}")
    print(f"MHE window from Python (update + solve) against bare OSQP solving the "
          f"same QPs, per sample; {repeats} repeats: min / median / max")  # fmt: skip
    for horizon in horizons:
        for constraint in Constraint:
            for bounded in (False, True):
                settings = MheSettings(horizon=horizon, constraint=constraint, bounded=bounded)
                rows = window_against_bare_osqp(vehicle, signals, settings, repeats)
                for label, mhe, bare in (
                    ("median", [r.mhe_median for r in rows], [r.bare_median for r in rows]),
                    ("mean", [r.mhe for r in rows], [r.bare for r in rows]),
                ):
                    mhe, bare = np.array(mhe), np.array(bare)
                    print(f"  {settings.label():30s} {label:6s} MHE {_spread(mhe)} us, bare OSQP "
                          f"{_spread(bare)} us, ratio {_spread(mhe / bare, '.2f')}")  # fmt: skip


def _bench_assembly(vehicle, signals, horizons: list[int], repeats: int) -> None:
    """The robust/bias window's QP assembly: sparse values against the dense matrix."""
    from wheelload.studies.bench.mhe import assembly_against_dense

    print(f"Robust/bias window QP assembly per sample, sparse values at the fixed pattern "
          f"against the dense matrix; {repeats} repeats of the medians: "
          "min / median / max")  # fmt: skip
    for horizon in horizons:
        for candidate in robust_candidates(horizon):
            if candidate.settings is None or not candidate.settings.extended:
                continue
            rows = assembly_against_dense(vehicle, signals, candidate.settings, repeats)
            sparse = np.array([r.sparse for r in rows])
            dense = np.array([r.dense for r in rows])
            print(f"  {candidate.name:52s} n = {rows[0].size:3d}, {rows[0].nnz:4d} values: "
                  f"sparse {_spread(sparse)} us, dense {_spread(dense)} us, "
                  f"dense / sparse {_spread(dense / sparse, '.1f')}")  # fmt: skip


def _spread(values: np.ndarray, fmt: str = ".1f") -> str:
    return " / ".join(format(v, fmt) for v in (values.min(), np.median(values), values.max()))


def _bench_c(
    vehicle,
    vehicle_path: Path,
    settings: MheSettings,
    signals,
    kf_step: float,
    repeats: int,
    name: str = "",
) -> None:
    """The generated C's time per sample: median over the log, then min/median/max of runs.

    Soft windows link the two-stage KF library in (its step is in the time).
    """
    from wheelload.estimators.codegen.mhe_build import build_mhe_library

    with tempfile.TemporaryDirectory() as folder:
        library = build_mhe_library(vehicle, settings, Path(folder), dt=0.01,
                                    vehicle_path=vehicle_path)  # fmt: skip
        results = [library.run(signals) for _ in range(max(repeats, 1))]
    medians = [float(np.median(r.solve_time)) * 1e6 for r in results]
    p99 = float(np.percentile(results[0].solve_time, 99)) * 1e6
    median = float(np.median(medians))
    label = (name or settings.label()) + " C"
    print(f"{label:38s} {median:10.1f} {p99:10.1f} {median / kf_step:10.2f} "
          f"(runs min {min(medians):.1f}, max {max(medians):.1f})")  # fmt: skip
