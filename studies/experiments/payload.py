"""Study ``payload``: the plant carries a payload its vehicle file does not know.

Payloads of 0, 80, 150 and 300 kg at three places, and a passenger getting in at a stop,
on every bundled vehicle; travel is measured from the file's reference state, so a
payload shows as static compression. Per method: pooled RMSE and its ratio to the
payload-0 run of the same vehicle, scenario and seed (the run where the file is exact),
and, from the estimators that report ``mass_properties``, the estimated mass and CG x
after 30 s of driving beside the truth. No paper gives this table.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.models.payload import Payload, loaded_mass_properties
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.drive.payload_schedule import PayloadChange, PayloadSchedule
from wheelload.studies.drive.scenarios import STOP_AND_GO_HOLD
from wheelload.studies.experiments.report.tables import markdown
from wheelload.studies.experiments.runs.common import Section, trials, truth_spec, window
from wheelload.studies.experiments.runs.context import Context
from wheelload.studies.experiments.runs.units import TrialResult, TrialSpec
from wheelload.studies.experiments.vehicles import vehicle_files

METHODS = ("kf", "C", "D")
SCENARIOS = ("iso-dlc", "brake-in-turn", "standstill")
QUICK_SCENARIOS = ("iso-dlc", "standstill")
STOP = "stop-and-go"  # the scenario of the passenger getting in
MASSES = (80.0, 150.0, 300.0)
QUICK_MASSES = (150.0,)
#: Where a payload sits: m from the vehicle file's sprung CG, ISO 8855 (x fwd, y left, z up).
PLACES = {
    "driver seat": (-0.1, 0.37, 0.10),
    "rear seats / boot": (-1.3, 0.0, 0.15),
    "roof box": (-0.4, 0.0, 0.95),
}
QUICK_PLACES = ("rear seats / boot",)
PASSENGER = Payload(mass=80.0, x=-0.1, y=-0.37, z=0.10)  # front passenger seat
PASSENGER_AT = 5.0  # s, the passenger gets in (the car stands until STOP_AND_GO_HOLD)
DRIVING = 30.0  # s of driving after which the mass properties are read
NOT_ESTIMATED = "not estimated"
EXACT = "0 kg (exact file)"


@dataclass(frozen=True, kw_only=True)
class Case:
    """One row: the plant's payload on one vehicle and scenario."""

    vehicle: str
    scenario: str
    label: str
    payload: PayloadSchedule | None  # None: the file's own car


def cases(vehicle: str, quick: bool) -> list[Case]:
    """The rows of one vehicle: per scenario the exact file and each payload; the passenger."""
    masses = QUICK_MASSES if quick else MASSES
    places = QUICK_PLACES if quick else tuple(PLACES)
    rows = []
    for scenario in QUICK_SCENARIOS if quick else SCENARIOS:
        rows.append(Case(vehicle=vehicle, scenario=scenario, label=EXACT, payload=None))
        for place in places:
            x, y, z = PLACES[place]
            for mass in masses:
                payload = PayloadSchedule(initial=Payload(mass=mass, x=x, y=y, z=z))
                label = f"{mass:.0f} kg, {place}"
                rows.append(Case(vehicle=vehicle, scenario=scenario, label=label, payload=payload))
    passenger = PayloadSchedule(change=PayloadChange(time=PASSENGER_AT, payload=PASSENGER))
    rows.append(Case(vehicle=vehicle, scenario=STOP, label=EXACT, payload=None))
    rows.append(
        Case(
            vehicle=vehicle,
            scenario=STOP,
            label=f"passenger {PASSENGER.mass:.0f} kg gets in at {PASSENGER_AT:g} s",
            payload=passenger,
        )
    )
    return rows


def reading_time(scenario: str) -> float:
    """When the mass properties are read: 30 s after driving off (or the log's end)."""
    return DRIVING + (STOP_AND_GO_HOLD if scenario == STOP else 0.0)


def true_mass_properties(text: str, case: Case) -> np.ndarray:
    """``[mass, cg_x, cg_y, cg_height]`` of the plant's car at the end of the run."""
    vehicle = vehicle_from_dict(tomllib.loads(text))
    payload = Payload(mass=0.0) if case.payload is None else case.payload.initial
    if case.payload is not None and case.payload.change is not None:
        payload = case.payload.change.payload
    return loaded_mass_properties(vehicle, payload)


def _rmse(result: TrialResult, name: str) -> float:
    table = result.metrics.get(name)
    return float("nan") if table is None else float(table.loc["pooled", "RMSE"])


def table_rows(rows: list[Case], results: list[TrialResult], texts: dict[str, str]) -> pd.DataFrame:
    """One row per case: RMSE and ratio per method, true and estimated mass and CG x."""
    exact = {
        (c.vehicle, c.scenario): r for c, r in zip(rows, results, strict=True) if c.payload is None
    }
    estimating = sorted({name for r in results for name in (r.mass_properties or {})})
    records = []
    for case, result in zip(rows, results, strict=True):
        record = {"vehicle": case.vehicle, "scenario": case.scenario, "payload": case.label}
        reference = exact[(case.vehicle, case.scenario)]
        for name in METHODS:
            rmse = _rmse(result, name)
            record[f"{name} RMSE [N]"] = rmse
            record[f"{name} ratio"] = rmse / _rmse(reference, name)
        truth = true_mass_properties(texts[case.vehicle], case)
        record["mass [kg]"] = truth[0]
        record["CG x [mm]"] = 1000.0 * truth[1]
        for name in estimating:
            found = (result.mass_properties or {}).get(name)
            record[f"{name} mass [kg]"] = np.nan if found is None else found[0]
            record[f"{name} CG x [mm]"] = np.nan if found is None else 1000.0 * found[1]
        if not estimating:
            record["estimated mass, CG x"] = NOT_ESTIMATED
        records.append(record)
    return pd.DataFrame.from_records(records)


def run(context: Context) -> Section:
    quick = context.settings.quick
    paths = (
        [Path(context.settings.vehicle_path)]
        if quick
        else vehicle_files(context.settings.vehicles_folder)
    )
    texts = {path.stem: path.read_text(encoding="utf-8") for path in paths}
    rows = [case for name in texts for case in cases(name, quick)]
    specs = []
    for case in rows:
        truth = replace(
            truth_spec(context, case.scenario, vehicle_text=texts[case.vehicle]),
            payload=case.payload,
        )
        specs.append(
            TrialSpec(
                truth=truth,
                vehicle_text=texts[case.vehicle],
                methods=METHODS,
                window=window(case.scenario),
                mass_properties_at=reading_time(case.scenario),
            )
        )
    results = trials(context, specs, "payload")
    table = table_rows(rows, results, texts)
    context.outputs.write_text("payload_table.csv", table.to_csv(index=False, float_format="%.3f"))
    failed = sorted({f"`{n}` ({t})" for r in results for n, t in r.errors.items()})
    places = "; ".join(
        f"{name} ({x:+.2f}, {y:+.2f}, {z:+.2f})" for name, (x, y, z) in PLACES.items()
    )
    shown = table.set_index(["vehicle", "scenario", "payload"])
    body = "\n\n".join(
        [
            "## Payload the vehicle file does not know (pooled RMSE [N], ratio to the exact file)",
            "The plant's sprung body carries a point mass; the estimators keep the bundled "
            "file, and travel is measured from its reference state (the payload shows as "
            f"static compression). Places (x, y, z) [m] from the sprung CG: {places}. The "
            f"passenger ({PASSENGER.mass:.0f} kg, front passenger seat) gets in at "
            f"{PASSENGER_AT:g} s of the {STOP} scenario (at rest {STOP_AND_GO_HOLD:g} s, then "
            "80 km/h and a lane change). Ratio: RMSE over the payload-0 run of the same "
            "vehicle, scenario and seed. Mass and CG x (from the file's whole-vehicle CG): "
            f"the truth, and the estimate {DRIVING:g} s after driving off (or at the log's "
            "end) from the methods that report it.",
            markdown(shown, digits=2),
            ("Methods that failed: " + ", ".join(failed) + ".") if failed else "",
        ]
    )
    return Section(title="Payload", markdown=body.rstrip() + "\n")
