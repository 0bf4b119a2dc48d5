"""One scenario end to end: simulate, measure, summarise, and describe for the metadata."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.models.conventions import WHEELS
from wheelload.models.vehicle.file import load_vehicle
from wheelload.studies.drive.payload_schedule import PayloadSchedule
from wheelload.studies.drive.scenario_log import file_hash, write_log
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenarios import SCENARIOS, scenario_run
from wheelload.studies.drive.sensors import MTI_1, SensorGrade, measure
from wheelload.studies.drive.simulation import Truth, simulate


@dataclass(frozen=True, kw_only=True)
class ScenarioResult:
    log: pd.DataFrame  # measured log columns (+ path columns of the truth)
    truth: Truth
    metadata: dict


def summary(frame: pd.DataFrame) -> dict:
    """Figures of a run: duration, distance, peak accelerations, path error, minimum loads."""
    loads = frame[[f"fz_{w}" for w in WHEELS]].to_numpy()
    return {
        "duration_s": float(frame["t"].iloc[-1] - frame["t"].iloc[0]),
        "distance_m": float(frame["s"].iloc[-1] - frame["s"].iloc[0]),
        "min_speed_mps": float(frame["vx"].min()),
        "max_speed_mps": float(frame["vx"].max()),
        "max_abs_ax_mps2": float(np.abs(frame["ax"]).max()),
        "max_abs_ay_mps2": float(np.abs(frame["ay"]).max()),
        "max_path_error_m": float(np.abs(frame["n"] - frame["target"]).max()),
        "max_lateral_deviation_m": float(np.abs(frame["n"]).max()),
        "min_edge_margin_m": float((frame["half_width"] - np.abs(frame["n"])).min()),
        "min_load_n": dict(zip(WHEELS, loads.min(axis=0).round(1).tolist(), strict=True)),
        "max_load_n": dict(zip(WHEELS, loads.max(axis=0).round(1).tolist(), strict=True)),
    }


def run_scenario(
    name: str,
    vehicle_path: str | Path,
    *,
    options: Options | None = None,
    noise: float = 1.0,
    output_rate: float = 100.0,
    internal_rate: float = 1000.0,
    allow_unusual: bool = False,
    payload: PayloadSchedule | None = None,
    sensors: SensorGrade = MTI_1,
) -> ScenarioResult:
    """Simulate scenario ``name`` with the vehicle file at ``vehicle_path``, measured by the
    sensors of grade ``sensors`` at noise scale ``noise``; with ``payload`` the plant
    carries it (recorded in the metadata's ``payload``), the file does not."""
    options = Options() if options is None else options
    vehicle = load_vehicle(vehicle_path, allow_unusual=allow_unusual)
    run = scenario_run(name, vehicle, options)
    truth = simulate(
        vehicle, run, internal_rate=internal_rate, output_rate=output_rate, payload=payload
    )
    rng = np.random.default_rng(np.random.SeedSequence([options.seed, 1]))
    log = measure(truth.frame, noise, rng, sensors)
    metadata = {
        "scenario": name,
        "vehicle": vehicle.name,
        "vehicle_file": str(Path(vehicle_path)),
        "vehicle_sha256": file_hash(vehicle_path),
        "seed": options.seed,
        "output_rate_hz": output_rate,
        "internal_rate_hz": internal_rate,
        "integrator": "RK4, fixed step, CasADi JIT",
        "noise_scale": noise,
        "sensor_grade": sensors.name,
        "options": dataclasses.asdict(options),
        "driver": dataclasses.asdict(run.tuning),
        "slip_control": dataclasses.asdict(run.slip_control),
        "wheelload_version": version("wheelload"),
        "reference_loads": "tyre normal force along the road normal [N], clean",
        "wall_time_s": truth.wall_time,
        "build_time_s": truth.build_time,
        "summary": summary(truth.frame),
    }
    if payload is not None:
        metadata["payload"] = payload.describe()
    return ScenarioResult(log=log, truth=truth, metadata=metadata)


def simulate_logs(
    names: list[str], folder: Path, vehicle_path: Path, allow_unusual: bool = False
) -> Iterator[tuple[str, Path, int]]:
    """Simulate the named scenarios on the plant, one after the other, each written to
    ``folder/NAME.parquet``: ``(name, path, samples)`` as each is written."""
    unknown = [name for name in names if name not in SCENARIOS]
    if unknown:
        raise ValueError(f"unknown scenario '{unknown[0]}'; choose from {', '.join(SCENARIOS)}")
    for name in names:
        result = run_scenario(name, vehicle_path, allow_unusual=allow_unusual)
        path = folder / f"{name}.parquet"
        write_log(result.log, path, result.metadata)
        yield name, path, len(result.log)
