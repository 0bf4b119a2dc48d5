"""``wheelload bench kf``: the two-stage KF's throughput (compiled run, step, numpy loop).

Printed, never asserted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wheelload.estimators import Sample
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.registry import build
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.bench.numpy_kf import joint_filter
from wheelload.studies.commands.options import add_vehicle_file_options
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench kf``."""
    parser = subparsers.add_parser("kf")
    parser.add_argument(
        "--samples", type=int, default=1_000_000, help="samples for the compiled run (default 1e6)"
    )
    parser.add_argument(
        "--loop-samples",
        type=int,
        default=20_000,
        help="samples for the per-sample Python loops (default 2e4)",
    )
    add_vehicle_file_options(parser)
    parser.set_defaults(handler=run)


def _tile(signals, n):
    """A log of n samples made by repeating a shorter one (time kept increasing)."""
    reps = -(-n // len(signals))
    dt = float(np.median(np.diff(signals.t)))
    t = np.arange(len(signals) * reps)[:n] * dt
    tile = lambda a: np.tile(a, (reps, 1))[:n] if a.ndim == 2 else np.tile(a, reps)[:n]  # noqa: E731
    return type(signals)(
        t=t,
        vx=tile(signals.vx),
        acc=tile(signals.acc),
        d=tile(signals.d),
        v=tile(signals.v),
        reference=None,
        source="bench",
    )


def run(args: argparse.Namespace) -> int:
    vehicle = load_vehicle(args.vehicle or example_vehicle_path(), allow_unusual=args.allow_unusual)
    base = synthetic_log(
        vehicle,
        slalom(duration=30.0),
        rate=1000.0,
        noise=SensorNoise(acceleration=0.05, travel=0.0002),
    )
    kf = build("kf", vehicle)
    start = time.perf_counter()
    kf.run(base.slice(0, 10))
    compile_time = time.perf_counter() - start

    big = _tile(base, args.samples)
    start = time.perf_counter()
    kf.run(big)
    run_time = time.perf_counter() - start

    small = _tile(base, args.loop_samples)
    start = time.perf_counter()
    joint_filter(small, kf.p, kf.tuning, kf.initial_state().x)
    numpy_time = time.perf_counter() - start

    n_step = min(args.loop_samples, 5000)
    dt = sample_intervals(small.t)
    state = kf.initial_state()
    start = time.perf_counter()
    for k in range(n_step):
        sample = Sample(d=small.d[k], v=small.v[k], acc=small.acc[k], vx=small.vx[k])
        state, _ = kf.step(state, sample, dt[k])
    step_time = time.perf_counter() - start

    per_run = run_time / args.samples * 1e6
    per_numpy = numpy_time / args.loop_samples * 1e6
    per_step = step_time / n_step * 1e6
    print(f"two-stage KF, {vehicle.name}, 1 kHz synthetic slalom log")
    print(f"  build or load the compiled C loop:      {compile_time:8.2f} s")
    print(
        f"  run(), compiled C loop,  {args.samples:>9} samples: {run_time:8.3f} s "
        f"= {per_run:7.3f} us/sample"
    )
    print(f"  plain numpy per-sample loop (joint update): {per_numpy:7.2f} us/sample")
    print(f"  Python step() per sample (compiled step):   {per_step:7.2f} us/sample")
    print(
        f"  run() is {per_numpy / per_run:.0f}x faster than the numpy loop and "
        f"{per_step / per_run:.0f}x faster than step()"
    )
    return 0
