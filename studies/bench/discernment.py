"""Model error, a changed car or a sensor fault: the KF on the plant with exact, loaded and
wrong vehicle files (``wheelload bench discernment``).

Each row is one plant log (a bundled car, a scenario, a sensor grade, seed 0) estimated by
the KF with one vehicle file: pooled RMSE against the reference loads, the channels the
fault monitor isolated, what the file check named, the online mass at the end, ±2σ
coverage, the mean per-wheel correlation of σ and ``|error|`` within the log, the mean σ,
and the mean per-wheel mean and spread (standard deviation) of ``|error|`` within the log
(a spread far below the mean is an error that hardly moves: a per-wheel offset, where a
correlation says little). Further cars (``vehicles``) are driven beside the bundled ones.

The no-travel case (:func:`without_travel`) stands for a front-only reference log of a real
car: the travel columns dropped, the rear references removed and ``ay`` :data:`LATE_AY` s
late; :func:`fit_no_travel` fits the reported σ's no-travel keys on such logs.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.identification.sigma_fit import SigmaFit, fit_sigma, sigma_data
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import load_vehicle
from wheelload.models.conventions import SUSPENSION_TABLES, WHEELS
from wheelload.models.inputs import TRAVEL, TRAVEL_RATE
from wheelload.models.payload import Payload
from wheelload.models.vehicle.description import SIGMA_KEYS, vehicle_from_dict
from wheelload.studies.drive.payload_schedule import PayloadSchedule
from wheelload.studies.drive.scenario_names import MANOEUVRES
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.sensors import sensor_grade
from wheelload.studies.experiments.faults.fault_injection import bundled_vehicles
from wheelload.studies.experiments.mismatch import mass_edits
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, scaled

SCENARIOS = MANOEUVRES
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
#: How late ``ay`` is in the no-travel case [s].
LATE_AY = 0.5
NO_TRAVEL = f"no travel, ay {LATE_AY:g} s late"
NO_TRAVEL_KEYS = tuple(key for key in SIGMA_KEYS if key.startswith("sigma_no_travel"))


def without_travel(log: pd.DataFrame, late: float = LATE_AY) -> pd.DataFrame:
    """``log`` without its travel and travel-rate columns; with ``late`` > 0 also without
    the rear reference loads and with ``ay`` ``late`` s late (its first value held)."""
    log = log.drop(columns=[c for c in (*TRAVEL, *TRAVEL_RATE) if c in log])
    if late <= 0.0:
        return log
    lag = int(round(late / float(np.median(np.diff(log["t"].to_numpy())))))
    ay = log["ay"].to_numpy()
    rear = [f"fz_{w}" for w in WHEELS[2:]]
    return log.drop(columns=rear).assign(ay=np.concatenate([np.full(lag, ay[0]), ay[:-lag]]))


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
    error_mean: float  # N, mean |error| per wheel, averaged over the wheels
    error_spread: float  # N, std of |error| per wheel, averaged over the wheels


def _row(car, scenario, grade, case, text, signals) -> Row:
    vehicle = vehicle_from_dict(tomllib.loads(text))
    estimate = build("kf", vehicle).run(signals)
    wheels = signals.reference_present  # the no-travel case: the front wheels
    error = (estimate.loads - signals.reference)[:, wheels]
    std = estimate.std[:, wheels]
    correlation = [
        np.corrcoef(std[:, i], np.abs(error[:, i]))[0, 1]
        for i in range(error.shape[1])
        if np.std(std[:, i]) > 0
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
        coverage=float(np.mean(np.abs(error) <= 2 * std)),
        correlation=float(np.mean(correlation)) if correlation else float("nan"),
        sigma=float(np.mean(std)),
        error_mean=float(np.mean(np.abs(error))),
        error_spread=float(np.mean(np.std(np.abs(error), axis=0))),
    )


def rows(
    grades: tuple[str, ...],
    quick: bool,
    payloads: bool = True,
    wrong: bool = True,
    vehicles: Sequence[Path] = (),
    no_travel: bool = False,
):
    """Every row, car by car (the bundled ones, then ``vehicles``), scenario by scenario
    (module docstring)."""
    scenarios = QUICK_SCENARIOS if quick else SCENARIOS
    for path in (*bundled_vehicles(), *vehicles):
        car = path.stem
        text = path.read_text(encoding="utf-8")
        off = text + "\n[filter.payload]\nestimate = false\n"
        for scenario in scenarios:
            for grade in grades:
                sensors = sensor_grade(grade)
                log = run_scenario(scenario, path, sensors=sensors).log
                # the plant's logs are wired right by construction; the wiring check's
                # physics does not hold for every car (the light car's stop-and-go)
                signals = signals_from_frame(log, source=scenario, wiring_checks=False)
                yield _row(car, scenario, grade, "exact", text, signals)
                if no_travel:
                    late = signals_from_frame(without_travel(log), source=scenario,
                                              wiring_checks=False)  # fmt: skip
                    yield _row(car, scenario, grade, NO_TRAVEL, text, late)
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
                        signals_loaded = signals_from_frame(
                            loaded, source=scenario, wiring_checks=False
                        )
                        yield _row(car, scenario, grade, label, text, signals_loaded)  # fmt: skip


def fit_no_travel(
    grades: tuple[str, ...], vehicles: Sequence[Path] = ()
) -> tuple[SigmaFit, list[tuple[str, float]]]:
    """The reported σ's no-travel keys fitted (:func:`~wheelload.estimators.identification.
    sigma_fit.fit_sigma`, the other keys held at the first file's) on every scenario of the
    cars at the ``grades``, each log without travel (:func:`without_travel`) as logged and
    with ``ay`` :data:`LATE_AY` s late; with each log's ±2σ coverage under the fit."""
    data, names = [], []
    paths = (*bundled_vehicles(), *vehicles)
    for path in paths:
        vehicle = load_vehicle(path)
        for scenario in SCENARIOS:
            for grade in grades:
                log = run_scenario(scenario, path, sensors=sensor_grade(grade)).log
                for late in (0.0, LATE_AY):
                    signals = signals_from_frame(without_travel(log, late), source=scenario,
                                                 wiring_checks=False)  # fmt: skip
                    data.append(sigma_data(build("kf", vehicle), signals).thinned(2))
                    names.append(f"{path.stem} {scenario} {grade}" + (" late" if late else ""))
    held = np.array(load_vehicle(paths[0]).filter.sigma_model())
    fit = fit_sigma(data, held=held, free=NO_TRAVEL_KEYS)
    covered = [float(np.mean(np.abs(d.error) <= 2 * d.std(fit.coefficients))) for d in data]
    return fit, list(zip(names, covered, strict=True))
