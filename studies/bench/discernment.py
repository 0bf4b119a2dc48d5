"""Model error, a changed car or a sensor fault: the KF on the plant with exact, loaded and
wrong vehicle files (``wheelload bench discernment``).

Each row is one plant log (a bundled car, a scenario, a sensor grade, seed 0) estimated by
the KF with one vehicle file: pooled RMSE against the reference loads, the channels the
fault monitor isolated, what the file check named, the online mass at the end, ±2σ
coverage, the mean per-wheel correlation of σ and ``|error|`` within the log, the mean σ.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models.conventions import SUSPENSION_TABLES
from wheelload.models.payload import Payload
from wheelload.models.vehicle.description import vehicle_from_dict
from wheelload.studies.drive.payload_schedule import PayloadSchedule
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.sensors import sensor_grade
from wheelload.studies.experiments.faults.fault_injection import bundled_vehicles
from wheelload.studies.experiments.mismatch import mass_edits
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, scaled

SCENARIOS = (
    "iso-dlc", "brake-in-turn", "accel-in-turn", "bounce-sweep", "slope-20",
    "chicane-bank-30", "chicane-incline-20", "wheel-lift", "standstill", "stop-and-go",
)  # fmt: skip
QUICK_SCENARIOS = ("iso-dlc", "brake-in-turn")
#: Payloads about the file's CG (x ahead, y left, z up) [kg, m]: rear seats, roof box.
PAYLOADS = {
    "150 kg rear": Payload(mass=150.0, x=-1.3, y=0.0, z=0.15),
    "300 kg rear": Payload(mass=300.0, x=-1.3, y=0.0, z=0.15),
    "75 kg roof": Payload(mass=75.0, x=-0.4, y=0.0, z=0.6),
}
#: One corner's travel zero for the zero rows [m].
ZERO = 3e-3
#: The motion ratio (damper over wheel travel) a file forgets: its front rates are then
#: the damper's, 1 / 0.7^2 = 2.04 times those at the wheel.
MOTION_RATIO = 0.7


def wrong_files(text: str) -> list[Variant]:
    """The issue's wrong files: bars removed, springs and mass 20 % off, and the front
    axle's spring, damper and bar rates given at the damper (a motion ratio forgotten)."""
    at_damper = 1.0 / MOTION_RATIO**2
    return [
        Variant(label="bars removed",
                edits=tuple(Edit(table=a, key="arb_rate", value=0.0) for a in SUSPENSION_TABLES)),
        Variant(label="springs -20 %",
                edits=tuple(scaled(text, a, "spring_rate", 0.8) for a in SUSPENSION_TABLES)),
        Variant(label="springs +20 %",
                edits=tuple(scaled(text, a, "spring_rate", 1.2) for a in SUSPENSION_TABLES)),
        Variant(label="mass -20 %", edits=mass_edits(text, 0.8)),
        Variant(label="mass +20 %", edits=mass_edits(text, 1.2)),
        Variant(label=f"front motion ratio {MOTION_RATIO:g} forgotten",
                edits=tuple(scaled(text, "suspension.front", key, at_damper)
                            for key in ("spring_rate", "damper_push", "damper_pull", "arb_rate"))),
    ]  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class Row:
    car: str
    scenario: str
    grade: str
    case: str  # "exact", "payload off", a payload, a wrong file, a travel zero
    rmse: float
    isolated: str
    named: str
    mass: float
    coverage: float
    correlation: float
    sigma: float


def _row(car, scenario, grade, case, text, signals) -> Row:
    vehicle = vehicle_from_dict(tomllib.loads(text))
    estimate = build("kf", vehicle).run(signals)
    error = estimate.loads - signals.reference
    correlation = [
        np.corrcoef(estimate.std[:, i], np.abs(error[:, i]))[0, 1]
        for i in range(4)
        if np.std(estimate.std[:, i]) > 0
    ]
    return Row(
        car=car,
        scenario=scenario,
        grade=grade,
        case=case,
        rmse=float(np.sqrt(np.mean(error**2))),
        isolated=", ".join(sorted({f.channel for f in estimate.sensor_faults})),
        named="; ".join(
            f"{m.name} {', '.join(f'{x:.4g}' for x in m.fitted_value)}"
            for m in estimate.model_errors
        ),
        mass=float(estimate.mass_properties[-1, 0]),
        coverage=float(np.mean(np.abs(error) <= 2 * estimate.std)),
        correlation=float(np.mean(correlation)) if correlation else float("nan"),
        sigma=float(np.mean(estimate.std)),
    )


def rows(grades: tuple[str, ...], quick: bool, payloads: bool = True, wrong: bool = True):
    """Every row, car by car, scenario by scenario (module docstring)."""
    scenarios = QUICK_SCENARIOS if quick else SCENARIOS
    for path in bundled_vehicles():
        car = path.stem
        text = path.read_text(encoding="utf-8")
        off = text + "\n[filter.payload]\nestimate = false\n"
        for scenario in scenarios:
            for grade in grades:
                sensors = sensor_grade(grade)
                log = run_scenario(scenario, path, sensors=sensors).log
                signals = signals_from_frame(log, source=scenario)
                yield _row(car, scenario, grade, "exact", text, signals)
                yield _row(car, scenario, grade, "payload off", off, signals)
                if wrong:
                    for variant in wrong_files(text):
                        yield _row(car, scenario, grade, variant.label, variant.apply(text),
                                   signals)  # fmt: skip
                    for k, channel in ((0, "d_fl"), (3, "d_rr")):
                        d = signals.d.copy()
                        d[:, k] += ZERO if k == 0 else -ZERO
                        shifted = type(signals)(**{**signals.__dict__, "d": d})
                        case = f"{channel} {'+' if k == 0 else '-'}{ZERO * 1e3:.0f} mm"
                        yield _row(car, scenario, grade, case, text, shifted)
                if payloads and grade == grades[0]:
                    for label, payload in PAYLOADS.items():
                        loaded = run_scenario(
                            scenario,
                            path,
                            sensors=sensors,
                            payload=PayloadSchedule(initial=payload),
                        ).log
                        signals_loaded = signals_from_frame(loaded, source=scenario)
                        yield _row(car, scenario, grade, label, text, signals_loaded)  # fmt: skip
