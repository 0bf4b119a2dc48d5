"""``wheelload bench fleet``: many logs through the batched C step, against the kernel and peers.

A fleet of ``--logs`` logs of ``--samples`` samples (windows of synthetic 1 kHz slalom
logs; the vehicle file with its payload filter off, so that the peers, which carry
none, compute the filter's numbers). Measured in the same run, ``--repeats`` times in
turn (min / median / max):

- :func:`~wheelload.estimators.codegen.batched.run_batched` over the fleet, 64 logs per
  call, ns per filter-step, against the kernel's own self-test figure
  (``batch-bench`` of 64 filters, the self-test linked against the very library
  ``run_batched`` loads; median of its passes) and against two peers doing the same KF
  step over all the fleet's filters at once: a batched NumPy update and a numba-jitted
  loop (:mod:`~wheelload.studies.bench.fleet_peers`; numba: the ``bench`` extra). The
  peers' loads are checked against ``run_batched``'s (largest difference printed);
- throughput of ``wheelload estimate`` over ``--files`` of the logs written as Parquet
  (reading, checks, the batched step, the summary) serially, on 2 local processes and
  on a ``distributed.LocalCluster`` of 2 workers: samples per second.

Printed, never asserted.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from wheelload.estimators.registry import build
from wheelload.models import load_vehicle
from wheelload.studies.bench.fleet import (
    batched_loads,
    fixed_mass,
    kernel_selftest,
    make_fleet,
    peer_arrays,
    time_peer,
    time_run_batched,
    write_fleet,
)
from wheelload.studies.bench.fleet_peers import numba_fleet, numpy_fleet
from wheelload.studies.bench.step_timing import selftest_median_ns, spread
from wheelload.studies.commands.options import add_allow_unusual, add_vehicle_option, vehicle_file
from wheelload.studies.pipeline.batch import BATCHED_TOLERANCE

#: run_batched per filter-step against the kernel's (issue 24's target).
KERNEL_TARGET = 1.5
#: Filters side by side in the kernel's self-test (run_batched's calls hold 64).
KERNEL_WIDTH = 64
#: Passes of the self-test per repeat; samples (batched steps) per pass.
PASSES, PASS_STEPS = 51, 200
#: The peers agree with the compiled path to rounding: the same equations in another
#: order (measured about 1e-15 relative); allowed relative to the largest load.
PEER_TOLERANCE = 1e-9


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench fleet``."""
    parser = subparsers.add_parser("fleet")
    add_vehicle_option(parser)
    parser.add_argument(
        "--log-count", dest="logs", type=int, default=1000, metavar="N",
        help="number of logs (default 1000)",
    )  # fmt: skip
    parser.add_argument("--samples", type=int, default=2000, help="samples per log (default 2000)")
    parser.add_argument("--repeats", type=int, default=3, help="repeats in turn (default 3)")
    parser.add_argument(
        "--files", type=int, default=100, help="logs written for the throughput runs (default 100)"
    )
    parser.add_argument(
        "--quick", action="store_true", help="128 logs of 1000 samples, 64 files, 2 repeats"
    )
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask LocalCluster")
    add_allow_unusual(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.quick:
        args.logs, args.samples, args.files, args.repeats = 128, 1000, 64, 2
    if args.logs < 1 or args.samples < 100 or args.repeats < 1 or args.files < 0:
        raise ValueError("--logs >= 1, --samples >= 100, --repeats >= 1, --files >= 0 needed")
    vehicle_path = vehicle_file(args)
    vehicle = fixed_mass(load_vehicle(vehicle_path, allow_unusual=args.allow_unusual))
    kf = build("kf", vehicle)
    fleet = make_fleet(vehicle, args.logs, args.samples)
    arrays = peer_arrays(kf, fleet)
    peers = {"numpy (batched over all filters)": numpy_fleet}
    numba_run = numba_fleet()
    if numba_run is not None:
        peers["numba (jitted loop)"] = numba_run
    with tempfile.TemporaryDirectory(prefix="wheelload_fleet_") as folder:
        selftest = kernel_selftest(kf, vehicle_path, Path(folder))
        _equality(kf, vehicle_path, fleet, arrays, peers)
        _step_times(kf, vehicle_path, fleet, arrays, peers, selftest, args)
        if numba_run is None:
            print(
                "  numba: not installed; its row is left out (pip install numba: the 'bench' extra)"
            )
        if args.files:
            _throughput(fleet, Path(folder), vehicle_path, args)
    return 0


def _equality(kf, vehicle_path, fleet, arrays, peers) -> None:
    """Print each peer's largest difference from run_batched's loads (and warm them up)."""
    first = min(len(fleet.windows), 64)
    reference = batched_loads(kf, vehicle_path, fleet, first)
    scale = float(np.abs(reference).max())
    print(
        f"fleet: {len(fleet.windows)} logs x {fleet.windows[0][2] - fleet.windows[0][1]} "
        f"samples, 1 kHz synthetic slalom windows, {kf.vehicle.name} (payload filter off)"
    )
    logs = fleet.logs[:4]
    single = max(
        float(np.abs(kf.run(log).loads - reference[:, k]).max()) for k, log in enumerate(logs)
    )
    print(
        f"  run_batched against TwoStageKF.run (the single-filter compiled loop) on {len(logs)} "
        f"logs: max |diff| {single:.2e} N = {single / scale:.1e} of the largest load "
        f"(tolerance {BATCHED_TOLERANCE:.0e}: FMA contraction in the fast build)"
    )
    for name, run in peers.items():
        start = time.perf_counter()
        loads = run(arrays)[:, :first]
        warm = time.perf_counter() - start
        difference = float(np.abs(loads - reference).max())
        verdict = "equal" if difference <= PEER_TOLERANCE * scale else "DIFFERENT"
        print(
            f"  {name}: loads of {first} logs {verdict} to run_batched's: max |diff| "
            f"{difference:.2e} N = {difference / scale:.1e} of the largest load "
            f"(tolerance {PEER_TOLERANCE:.0e}); first run {warm:.1f} s (numba: compile)"
        )


def _step_times(kf, vehicle_path, fleet, arrays, peers, selftest, args) -> None:
    """Print ns per filter-step of run_batched, the kernel and the peers, and ratios."""
    times: dict[str, list[float]] = {"run_batched": [], "kernel": []}
    times.update({name: [] for name in peers})
    for _ in range(args.repeats):  # in turn: every path meets the same machine load
        times["kernel"].append(
            selftest_median_ns(selftest, "batch-bench", PASS_STEPS, PASSES, KERNEL_WIDTH)
        )
        times["run_batched"].append(time_run_batched(kf, vehicle_path, fleet))
        for name, run in peers.items():
            times[name].append(time_peer(run, arrays))
    print(f"ns per filter-step, {args.repeats} repeats in turn (min / median / max)")
    print(
        f"  kernel self-test, batch of {KERNEL_WIDTH} (median of {PASSES} passes): "
        f"{spread(times['kernel'])}"
    )
    print(f"  run_batched, {KERNEL_WIDTH} logs per call:  {spread(times['run_batched'])}")
    ratios = [r / k for r, k in zip(times["run_batched"], times["kernel"])]
    print(f"    run_batched / kernel: {spread(ratios)} (target <= {KERNEL_TARGET:g})")
    for name in peers:
        print(f"  {name}: {spread(times[name])}")
        ratios = [p / r for p, r in zip(times[name], times["run_batched"])]
        print(f"    run_batched is {spread(ratios)} x faster")


def _throughput(fleet, folder: Path, vehicle_path: Path, args) -> None:
    """Print samples/s of the many-logs pipeline: 1 worker, 2 processes, LocalCluster(2)."""
    import contextlib

    from wheelload.studies.pipeline.batch import EstimateSettings, run_logs

    paths = write_fleet(fleet, folder, min(args.files, len(fleet.windows)))
    samples = sum(stop - start for _, start, stop in fleet.windows[: len(paths)])
    settings = EstimateSettings(vehicle=vehicle_path, allow_unusual=args.allow_unusual)
    variants: dict[str, dict] = {"1 worker": {}, "2 local processes": {"workers": 2}}
    with contextlib.ExitStack() as stack:
        if not args.no_dask:
            from distributed import LocalCluster

            cluster = stack.enter_context(
                LocalCluster(
                    n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
                )
            )
            variants["dask LocalCluster (2)"] = {"dask_address": cluster.scheduler_address}
        for options in variants.values():  # warm up: imports, the libraries in each worker
            run_logs(paths[:8], settings, None, progress=False, **options)
        rates: dict[str, list[float]] = {name: [] for name in variants}
        errors = 0
        for _ in range(args.repeats):
            for name, options in variants.items():
                start = time.perf_counter()
                table = run_logs(paths, settings, None, progress=False, **options)
                rates[name].append(samples / (time.perf_counter() - start))
                if "error" in table.columns:
                    errors = max(errors, int((table["error"] != "").sum()))
    print(
        f"wheelload estimate over {len(paths)} Parquet logs ({samples} samples; read, checks, "
        f"batched step, summary) [samples/s]"
    )
    serial = statistics.median(rates["1 worker"])
    for name, values in rates.items():
        print(
            f"  {name:22s} {spread(values)}  ({statistics.median(values) / serial:.2f} x 1 worker)"
        )
    if errors:
        print(f"  {errors} logs gave an error row (not estimated)")
