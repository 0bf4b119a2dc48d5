"""``wheelload bench speed``: the per-sample step, the batched C and the C step's chain bound.

Each figure is printed beside its alternative measured in the same run,
over ``--repeats`` alternating repeats (min / median / max of the ratio):

- :meth:`TwoStageKF.step` (compiled step on preallocated buffers) against
  filterpy's ``KalmanFilter`` doing the same prediction and two sequential
  updates (filterpy: the ``bench`` extra), and against the CasADi reference
  step;
- the generated library's batched step (``--batch`` filters side by side)
  against its single step, double and float, built with the Makefile's
  default ``CFLAGS`` (-O2) and with its ``FAST_CFLAGS``; and the batched float
  step per filter against the single double step;
- :func:`~wheelload.estimators.codegen.batched.run_batched` over ``--logs`` logs
  against :meth:`TwoStageKF.run` on each (what ``estimate`` over many logs
  and the Monte Carlo study now use, against what they used);
- the single C step (double, fastest of short passes) against its
  dependency-chain bound (the longest chain of the kernel's instructions at
  :data:`~wheelload.estimators.kernels.c_emitter.LATENCY` cycles each) and its
  throughput bound (the compiled kernel's instruction mix,
  :mod:`~wheelload.studies.bench.c_step_bounds`), in cycles of the
  measured clock; and against the same step with plain C99 selects built
  without ``-freciprocal-math`` (the step before the branch-free selects).

Printed, never asserted.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from wheelload.estimators.codegen.kf import FAST_CFLAGS, STRICT_CFLAGS, CodegenOptions
from wheelload.estimators.kernels.c_emitter import Precision, critical_path, flop_count
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.registry import build
from wheelload.models import load_vehicle
from wheelload.studies.bench.c_step_bounds import (
    IMUL_LATENCY,
    compiled_mix,
    measured_clock_mhz,
)
from wheelload.studies.bench.step_timing import (
    batched_against_run,
    cpu_mhz,
    fast_selftest,
    live_steps,
    per_call_us,
    python_steps,
    selftest_ns,
    single_and_batched_ns,
    spread,
)
from wheelload.studies.commands.options import add_allow_unusual, add_vehicle_option, vehicle_file
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

STEP_TARGET = 10.0  # µs per TwoStageKF.step
FILTERPY_TARGET = 10.0  # times faster than filterpy
BATCH_TARGETS = {Precision.DOUBLE: 4.0, Precision.FLOAT: 8.0}  # throughput vs single step
CHAIN_TARGET = 1.3  # single C step / dependency-chain bound
FLOAT_BATCH_TARGET = 0.25  # batched float per filter / single double step
#: Passes of each C timing (of --samples filter-steps each): short passes, the
#: fastest taken, so that a pass rarely loses the core on a shared machine.
PASSES = 101


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench speed``."""
    parser = subparsers.add_parser("speed")
    add_vehicle_option(parser)
    parser.add_argument("--repeats", type=int, default=5, help="alternating repeats (default 5)")
    parser.add_argument("--steps", type=int, default=2000, help="Python steps per repeat")
    parser.add_argument(
        "--samples",
        type=int,
        default=1000,
        help=f"samples: C (filter-)steps per timing pass, fastest of {PASSES} (default 1000)",
    )
    parser.add_argument("--batch", type=int, default=16, help="filters side by side (1-64)")
    parser.add_argument(
        "--log-count",
        dest="logs",
        type=int,
        default=16,
        metavar="N",
        help="number of logs for run_batched vs run (default 16)",
    )
    parser.add_argument(
        "--log-samples", type=int, default=20_000, help="samples per log (default 2e4, 1 kHz)"
    )
    add_allow_unusual(parser)
    parser.set_defaults(handler=run)


def logs_vs_run(vehicle_path: Path, kf: TwoStageKF, args: argparse.Namespace) -> None:
    """Print run_batched over many logs against run on each, us per sample."""
    vehicle = kf.vehicle
    duration = args.log_samples / 1000.0
    logs = [
        synthetic_log(vehicle, slalom(duration=duration), rate=1000.0, seed=seed,
                      noise=SensorNoise(acceleration=0.05, travel=0.0003))
        for seed in range(args.logs)
    ]  # fmt: skip
    batched, single = batched_against_run(kf, vehicle_path, logs, args.repeats)
    ratios = [s / b for s, b in zip(single, batched)]
    print(f"{args.logs} logs of {args.log_samples} samples [us per sample]")
    print(f"  run_batched (side by side, batched C): {spread(batched)}")
    print(f"  TwoStageKF.run on each log:            {spread(single)}")
    print(f"  run_batched is {spread(ratios)} x faster")


def run(args: argparse.Namespace) -> int:
    if not 1 <= args.batch <= 64:
        raise ValueError(f"--batch must be 1..64, got {args.batch}")
    if args.repeats < 1 or args.steps < 10 or args.samples < 100:
        raise ValueError("--repeats >= 1, --steps >= 10 and --samples >= 100 are needed")
    if args.logs < 1 or args.log_samples < 100:
        raise ValueError("--logs >= 1 and --log-samples >= 100 are needed")
    vehicle_path = vehicle_file(args)
    vehicle = load_vehicle(vehicle_path, allow_unusual=args.allow_unusual)
    kf = build("kf", vehicle)
    signals = synthetic_log(
        vehicle, slalom(duration=30.0), noise=SensorNoise(acceleration=0.05, travel=0.0003)
    )
    n = min(args.steps, len(signals))
    fast, reference, filterpy = python_steps(kf, signals, n)
    fast(0)  # compile (or load) the step
    lean = live_steps(kf, signals, n)
    print(f"speed, {vehicle.name}; each ratio from alternating repeats, min / median / max")
    print(f"Python step (x {n} steps, {args.repeats} repeats) [us per step]")
    timings: dict[str, list[float]] = {"fast": [], "reference": [], "filterpy": [], "lean": []}
    for _ in range(args.repeats):
        timings["fast"].append(per_call_us(fast, n))
        timings["lean"].append(per_call_us(lean, n))
        timings["reference"].append(per_call_us(reference, min(n, 500)))
        if filterpy is not None:
            timings["filterpy"].append(per_call_us(filterpy, n))
    print(f"  TwoStageKF.step (compiled, buffers): {spread(timings['fast'])}"
          f"  (target <= {STEP_TARGET:g} us)")  # fmt: skip
    print(f"  reference_step (CasADi VM + numpy): {spread(timings['reference'])}")
    ratios = [r / f for r, f in zip(timings["reference"], timings["fast"])]
    print(f"  step is {spread(ratios)} x faster than reference_step")
    if filterpy is None:
        print("  filterpy: not installed; install the 'bench' extra (pip install filterpy)")
    else:
        print(f"  filterpy KalmanFilter, 2 updates:    {spread(timings['filterpy'])}")
        ratios = [p / f for p, f in zip(timings["filterpy"], timings["fast"])]
        print(f"  step is {spread(ratios)} x faster than filterpy (target >= {FILTERPY_TARGET:g})")
    print(f"  TwoStageKF.live().update (lean):    {spread(timings['lean'])}")
    if filterpy is not None:
        ratios = [p / f for p, f in zip(timings["filterpy"], timings["lean"])]
        print(f"  live update is {spread(ratios)} x faster than filterpy "
              f"(target >= {FILTERPY_TARGET:g})")  # fmt: skip

    logs_vs_run(vehicle_path, kf, args)
    with tempfile.TemporaryDirectory(prefix="wheelload_speed_") as folder:
        for name, flags in (("CFLAGS (default)", STRICT_CFLAGS), ("FAST_CFLAGS", FAST_CFLAGS)):
            print(f"Generated C, {name}: {' '.join(flags)}")
            times = {p: batch_vs_single(vehicle_path, Path(folder) / name[:6], p, flags, args)
                     for p in Precision}  # fmt: skip
            ratios = [f / d for f, d in zip(times[Precision.FLOAT][1], times[Precision.DOUBLE][0])]
            print(f"  batched float / single double step {spread(ratios)} "
                  f"(target <= {FLOAT_BATCH_TARGET:g})")  # fmt: skip
        single_step_vs_bounds(vehicle_path, Path(folder), args)
    return 0


def batch_vs_single(vehicle_path: Path, folder: Path, precision: Precision, flags, args):
    """Print and return the single and batched step's ns per filter-step (``flags``)."""
    _, binary = fast_selftest(
        vehicle_path, folder / precision.value, CodegenOptions(precision=precision), flags,
        args.allow_unusual,
    )  # fmt: skip
    single, batched = single_and_batched_ns(binary, args.samples, PASSES, args.batch, args.repeats)
    ratios = [s / b for s, b in zip(single, batched)]
    print(f"  {precision.value}: single step {spread(single)} ns; batch of {args.batch}: "
          f"{spread(batched)} ns per filter-step")  # fmt: skip
    print(f"    batched throughput {spread(ratios)} x the single step "
          f"(target >= {BATCH_TARGETS[precision]:g})")  # fmt: skip
    return single, batched


#: The single step as it was generated before the branch-free selects: plain C99
#: selects, FAST_CFLAGS without -freciprocal-math.
PLAIN_FLAGS = tuple(flag for flag in FAST_CFLAGS if flag != "-freciprocal-math")


def single_step_vs_bounds(vehicle_path: Path, folder: Path, args) -> None:
    """Print the single C step (double) against its chain and throughput bounds.

    Two builds side by side: this emitter (branch-free selects, FAST_CFLAGS)
    and the plain C99 selects with FAST_CFLAGS without -freciprocal-math
    (the step before them); for each, the compiled kernel's instruction mix.
    """
    nominal, clock = cpu_mhz(), measured_clock_mhz(folder)
    variants = {
        "branch-free selects, FAST_CFLAGS": (CodegenOptions(), FAST_CFLAGS),
        "plain C99 selects, no -freciprocal-math": (
            CodegenOptions(branch_free=False),
            PLAIN_FLAGS,
        ),
    }
    built = {
        name: fast_selftest(vehicle_path, folder / f"single{k}", options, flags, args.allow_unusual)
        for k, (name, (options, flags)) in enumerate(variants.items())
    }
    times: dict[str, list[float]] = {name: [] for name in variants}
    for _ in range(args.repeats):
        for name, (_, binary) in built.items():
            times[name].append(selftest_ns(binary, "bench", args.samples, PASSES))
    kernel = next(iter(built.values()))[0].kernel
    chain = critical_path(kernel)
    mhz = clock or nominal
    print(f"Single C step (double) against its bounds; clock {_mhz(clock)} measured "
          f"(dependent imul, {IMUL_LATENCY} cycles each), {_mhz(nominal)} nominal "
          "(/proc/cpuinfo)")  # fmt: skip
    in_ns = f" = {chain / mhz * 1e3:.0f} ns" if mhz else ""
    print(f"  kernel: {kernel.n_instructions()} CasADi instructions, {flop_count(kernel)} FLOPs; "
          f"chain bound {chain} cycles{in_ns}")  # fmt: skip
    for name, (library, _) in built.items():
        options, flags = variants[name]
        mix = compiled_mix(library.source, f"{options.prefix}_kernel", flags)
        cycles = [t * mhz * 1e-3 for t in times[name]] if mhz else []
        print(f"  {name}: {spread(times[name])} ns per step"
              + (f" = {spread(cycles)} cycles" if cycles else ""))  # fmt: skip
        if mix is not None:
            bounds = ", ".join(f"{k} {v:.0f}" for k, v in mix.bounds().items())
            print(f"    compiled kernel: {mix.instructions} instructions ({mix.multiply} mul/FMA/"
                  f"blend, {mix.add} add/compare/min/max, {mix.divide} div/sqrt, {mix.stack} "
                  f"stack accesses, {mix.branches} branches)")  # fmt: skip
            print(f"    throughput bound {mix.throughput_bound():.0f} cycles ({bounds})")
        if cycles:
            print(f"    step / chain bound {spread([c / chain for c in cycles])} "
                  f"(target <= {CHAIN_TARGET:g})")  # fmt: skip
            if mix is not None:
                bound = mix.throughput_bound()
                print(f"    step / throughput bound {spread([c / bound for c in cycles])}")
    first, second = variants
    ratios = [b / a for a, b in zip(times[first], times[second])]
    print(f"  {first} is {spread(ratios)} x faster than {second}")


def _mhz(value: float | None) -> str:
    return "unknown" if value is None else f"{value:.0f} MHz"
