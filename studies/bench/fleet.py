"""Workloads of ``wheelload bench fleet``: many logs through the batched C step and its peers.

A fleet is ``count`` windows of ``samples`` samples of a few synthetic 1 kHz slalom logs
(views, no copies). Each function here returns times or results; the command prints them.
"""

from __future__ import annotations

import dataclasses
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wheelload.estimators.codegen.batched import MAX_FILTERS, PREFIX, batch_library, run_batched
from wheelload.estimators.codegen.kf import CodegenOptions, generate
from wheelload.estimators.kernels.c_emitter import Precision
from wheelload.estimators.kf.tuning import nominal_interval
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.output_files import write_frame
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, Vehicle
from wheelload.studies.bench.fleet_peers import FleetArrays, fleet_arrays
from wheelload.studies.drive.synthetic import SensorNoise, slalom, synthetic_log

#: Synthetic logs the fleet's windows are cut from.
BASES = 4
NOISE = SensorNoise(acceleration=0.05, travel=0.0003)


def fixed_mass(vehicle: Vehicle) -> Vehicle:
    """``vehicle`` with the payload filter off: the file's mass and CG held (the peers carry
    no payload filter, so they give the filter's numbers only so)."""
    payload = dataclasses.replace(vehicle.filter.payload, estimate=False)
    return vehicle.replace(filter=dataclasses.replace(vehicle.filter, payload=payload))


@dataclass(frozen=True, kw_only=True)
class Fleet:
    """``len(windows)`` logs: windows ``(base, start, stop)`` of the base logs."""

    bases: list[Signals]
    windows: list[tuple[int, int, int]]

    @property
    def logs(self) -> list[Signals]:
        return [self.bases[k].slice(start, stop) for k, start, stop in self.windows]

    @property
    def filter_steps(self) -> int:
        return sum(stop - start for _, start, stop in self.windows)


def make_fleet(vehicle: Vehicle, count: int, samples: int) -> Fleet:
    """``count`` windows of ``samples`` samples, each starting elsewhere in one of
    :data:`BASES` synthetic slalom logs of their own noise."""
    duration = max(30.0, 4 * samples / 1000.0)
    bases = [
        synthetic_log(vehicle, slalom(duration=duration), rate=1000.0, seed=seed, noise=NOISE)
        for seed in range(BASES)
    ]
    span = len(bases[0]) - samples
    windows = [(k % BASES, (k * 97) % span, (k * 97) % span + samples) for k in range(count)]
    return Fleet(bases=bases, windows=windows)


def peer_arrays(kf: TwoStageKF, fleet: Fleet) -> FleetArrays:
    """The peers' inputs for the fleet, each log's noise at the nominal interval the
    batched step uses for it."""
    tunings = [kf.tuning_for(nominal_interval(log.t)) for log in fleet.logs]
    weight = kf.parameters.mass * GRAVITY
    return fleet_arrays(fleet.bases, fleet.windows, kf.p, tunings, kf.initial_state().x, weight)


def batched_loads(kf: TwoStageKF, vehicle_path: Path, fleet: Fleet, first: int) -> np.ndarray:
    """Loads (T, first, 4) of the first ``first`` logs by :func:`run_batched`."""
    estimates = run_batched(kf, vehicle_path, fleet.logs[:first])
    return np.stack([estimate.loads for estimate in estimates], axis=1)


def time_run_batched(kf: TwoStageKF, vehicle_path: Path, fleet: Fleet) -> float:
    """ns per filter-step of :func:`run_batched` over the fleet, :data:`MAX_FILTERS` logs per
    call (the estimates of a call dropped before the next: memory bounded by one batch)."""
    logs = fleet.logs
    start = time.perf_counter()
    for first in range(0, len(logs), MAX_FILTERS):
        run_batched(kf, vehicle_path, logs[first : first + MAX_FILTERS])
    return (time.perf_counter() - start) / fleet.filter_steps * 1e9


def time_peer(run, arrays: FleetArrays) -> float:
    """ns per filter-step of a peer ``run(arrays)``."""
    start = time.perf_counter()
    run(arrays)
    return (time.perf_counter() - start) / arrays.dt.size * 1e9


def kernel_selftest(kf: TwoStageKF, vehicle_path: Path, folder: Path) -> Path:
    """The generated self-test linked against the very library :func:`run_batched` loads
    (the same machine code of the kernel; only the small test program is compiled)."""
    library = batch_library(kf.step_function, Path(vehicle_path))
    options = CodegenOptions(precision=Precision.DOUBLE, prefix=PREFIX)
    generated = generate(vehicle_path, folder, options, kf.step_function, allow_unusual=True)
    binary = folder / "selftest"
    command = ["gcc", "-O2", "-std=c99", "-o", str(binary), str(generated.selftest),
               str(library.path), f"-Wl,-rpath,{library.path.parent}", "-lm"]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{result.stderr}")
    return binary


def write_fleet(fleet: Fleet, folder: Path, count: int) -> list[Path]:
    """The first ``count`` logs of the fleet as Parquet files in ``folder``."""
    paths = []
    for k, log in enumerate(fleet.logs[:count]):
        path = folder / f"log{k:05d}.parquet"
        write_frame(log.to_frame(), path)
        paths.append(path)
    return paths
