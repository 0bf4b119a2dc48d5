"""``wheelload bench codegen``: time the generated C step beside Python and filterpy.

Prints, from one run on this machine, the median time per step of the
generated C step (double and float, runtime parameters), the Python
per-sample :meth:`TwoStageKF.step`, and filterpy's ``KalmanFilter`` doing the
same prediction and two sequential updates (if filterpy, the ``bench``
extra, is installed), and the FLOPs per step of the generated step against
the machine's scalar peak. Printed, never asserted.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from wheelload.estimators.kernels.c_emitter import Precision, operation_counts
from wheelload.estimators.registry import build
from wheelload.models import load_vehicle
from wheelload.studies.bench.step_timing import c_step_ns, cpu_mhz, filterpy_step_ns, python_step_ns
from wheelload.studies.commands.options import add_allow_unusual, add_vehicle_option, vehicle_file
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

TARGET_NS = 150.0
#: Scalar floating-point operations a core can issue per cycle: two multiply
#: (FMA) and two add pipes on AMD Zen 3-5 and Intel Golden Cove class cores.
SCALAR_OPS_PER_CYCLE = 4


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench codegen``."""
    parser = subparsers.add_parser("codegen")
    add_vehicle_option(parser)
    parser.add_argument("--samples", type=int, default=20_000, help="C samples per repeat")
    parser.add_argument("--repeats", type=int, default=51, help="C repeats (median taken)")
    parser.add_argument("--python-samples", type=int, default=2000, help="Python steps timed")
    add_allow_unusual(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    vehicle_path = vehicle_file(args)
    vehicle = load_vehicle(vehicle_path, allow_unusual=args.allow_unusual)
    with tempfile.TemporaryDirectory(prefix="wheelload_bench_") as folder:
        c_double, c_double_min, library = c_step_ns(
            vehicle_path,
            Precision.DOUBLE,
            Path(folder),
            args.samples,
            args.repeats,
            args.allow_unusual,
        )
        c_float, c_float_min, _ = c_step_ns(
            vehicle_path,
            Precision.FLOAT,
            Path(folder),
            args.samples,
            args.repeats,
            args.allow_unusual,
        )
    kf = build("kf", vehicle)
    signals = synthetic_log(
        vehicle, slalom(duration=30.0), noise=SensorNoise(acceleration=0.05, travel=0.0003)
    )
    n = min(args.python_samples, len(signals))
    py = python_step_ns(kf, signals, n)
    fp = filterpy_step_ns(kf, signals, n)

    flops = library.flops
    counts = operation_counts(library.kernel)
    arithmetic = ", ".join(
        f"{counts[op]} {op}" for op in ("mul", "add", "sub", "div", "sqrt", "fmax", "neg")
    )
    print(f"two-stage KF step, {vehicle.name}, median ns per step (one run, this machine)")
    for name, median, least in (
        ("double", c_double, c_double_min),
        ("float", c_float, c_float_min),
    ):
        print(f"  generated C, {name + ':':20s}{median:10.1f} ns  (fastest repeat {least:.1f})")
    print(f"  Python TwoStageKF.step:          {py:10.1f} ns  ({py / c_double:.0f}x C double)")
    if fp is None:
        print("  filterpy KalmanFilter:           skipped (install the 'bench' extra: filterpy)")
    else:
        print(f"  filterpy KalmanFilter, 2 updates:{fp:10.1f} ns  ({fp / c_double:.0f}x C double)")
    verdict = "met" if max(c_double, c_float) < TARGET_NS else "missed"
    print(f"  target {TARGET_NS:.0f} ns for the C step: {verdict}")
    print(f"FLOPs per step (generated kernel): {flops} ({arithmetic})")
    mhz = cpu_mhz()
    if mhz is None:
        print("  scalar peak unknown (no clock frequency in /proc/cpuinfo)")
        return 0
    peak = mhz * 1e-3 * SCALAR_OPS_PER_CYCLE
    for name, ns in (("double", c_double), ("float", c_float)):
        rate = flops / ns
        print(
            f"  C {name}: {rate:.2f} GFLOP/s = {100 * rate / peak:.0f} % of the scalar peak "
            f"{peak:.1f} GFLOP/s ({mhz:.0f} MHz x {SCALAR_OPS_PER_CYCLE} ops/cycle)"
        )
    return 0
