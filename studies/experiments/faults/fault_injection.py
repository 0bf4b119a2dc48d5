"""Fault-injection study: the two-stage KF with and without its guards on faulty plant logs.

Each scenario is simulated once (``run_scenario``, measured with the
standard sensor models); faults are then injected into the measured log
from 20 % of its duration:

- ``stuck``: the FL travel holds its last value (rate 0);
- ``drift``: the FL travel drifts by 1 mm/s (rate +1 mm/s);
- ``dead``: the FL travel reads the bottom of its stroke, -75 mm (rate 0);
- ``ay-bias``: +0.5 m/s^2 on ay;
- ``dropout``: every sensor channel missing for 2 s;
- ``spikes``: one single-sample spike every 2 s on each of the 12 channels
  (travel +30 mm, rate +1 m/s, acceleration +15 m/s^2, speed +20 m/s) at
  random samples.

Scores: pooled RMSE against the plant's reference loads with the guards
(``after``) and with every guard threshold set out of reach (``before``,
the filter of the previous release: the step is the same otherwise), the
detection delay of the faulted channel, and the false alarms per hour of
the fault monitor on the clean logs of every bundled scenario.

Command: ``wheelload bench faults`` (``--quick``: iso-dlc and brake-in-turn only;
``--seeds N``: the clean logs with N seeds of road and sensors; ``--alarms-only``:
the false alarms, clean-log RMSE and each channel's clean-log fault floor only;
``--vehicle FILE``: repeatable, default both bundled vehicles; ``--model
full|paper|both``: the vehicle file's model, the paper's, or both on the same logs;
``--progress``: hours and alarms so far after each vehicle and seed; ``--spikes``: the
isolation table of :mod:`wheelload.studies.experiments.faults.fault_spikes` only). The false
alarms print the hours of clean driving, the alarm count and the 95 % Poisson upper bound on
the rate.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import chi2

from wheelload.estimators import (
    FAULT_CHANNELS,
    GUARDS_OFF,
    GuardSettings,
    Signals,
    guard_settings_for,
)
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.drive.scenarios import SCENARIOS
from wheelload.studies.experiments.equilibrium_residuals import paper_model
from wheelload.studies.experiments.faults.fault_spikes import SPIKE_SCENARIOS, spike_table
from wheelload.studies.metrics import wheel_metrics

FAULT_SCENARIOS = ("iso-dlc", "hockenheim", "brake-in-turn")
ONSET = 0.2  # fraction of the log before a fault starts
DRIFT_RATE = 1e-3  # m/s
DEAD_READING = -0.075  # m, bottom of a 150 mm stroke
AY_BIAS = 0.5  # m/s^2
DROPOUT = 2.0  # s
SPIKE_PERIOD = 2.0  # s
SPIKES = {"d": 0.030, "v": 1.0, "acc": 15.0, "vx": 20.0}


@dataclass(frozen=True, kw_only=True)
class Fault:
    """An injected fault: a function of (signals, onset index, rng) and the channel it hits."""

    name: str
    channel: str | None  # the fault monitor's channel name, or None
    inject: Callable[[Signals, int, np.random.Generator], Signals]


def _stuck(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    d, v = s.d.copy(), s.v.copy()
    d[k:, 0] = d[k - 1, 0]
    v[k:, 0] = 0.0
    return dataclasses.replace(s, d=d, v=v)


def _drift(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    d, v = s.d.copy(), s.v.copy()
    d[k:, 0] += DRIFT_RATE * (s.t[k:] - s.t[k])
    v[k:, 0] += DRIFT_RATE
    return dataclasses.replace(s, d=d, v=v)


def _dead(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    d, v = s.d.copy(), s.v.copy()
    d[k:, 0] = DEAD_READING
    v[k:, 0] = 0.0
    return dataclasses.replace(s, d=d, v=v)


def _ay_bias(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    acc = s.acc.copy()
    acc[k:, 1] += AY_BIAS
    return dataclasses.replace(s, acc=acc)


def _dropout(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    gap = (s.t >= s.t[k]) & (s.t < s.t[k] + DROPOUT)
    d, v, acc, vx = s.d.copy(), s.v.copy(), s.acc.copy(), s.vx.copy()
    for array in (d, v, acc):
        array[gap] = np.nan
    vx[gap] = np.nan
    return dataclasses.replace(s, d=d, v=v, acc=acc, vx=vx)


def _spikes(s: Signals, k: int, rng: np.random.Generator) -> Signals:
    d, v, acc, vx = s.d.copy(), s.v.copy(), s.acc.copy(), s.vx.copy()
    step = max(1, int(round(SPIKE_PERIOD / float(np.median(np.diff(s.t))))))
    channels = [(d, i, SPIKES["d"]) for i in range(4)]
    channels += [(v, i, SPIKES["v"]) for i in range(4)]
    channels += [(acc, i, SPIKES["acc"]) for i in range(3)]
    for start in range(0, len(s) - step, step):
        rows = start + rng.choice(step, size=len(channels) + 1, replace=False)
        for (array, i, size), row in zip(channels, rows[:-1], strict=True):
            array[row, i] += size
        vx[rows[-1]] += SPIKES["vx"]
    return dataclasses.replace(s, d=d, v=v, acc=acc, vx=vx)


FAULTS = (
    Fault(name="clean", channel=None, inject=lambda s, k, rng: s),
    Fault(name="stuck", channel="d_fl", inject=_stuck),
    Fault(name="drift", channel="d_fl", inject=_drift),
    Fault(name="dead", channel="d_fl", inject=_dead),
    Fault(name="ay-bias", channel="ay", inject=_ay_bias),
    Fault(name="dropout", channel=None, inject=_dropout),
    Fault(name="spikes", channel=None, inject=_spikes),
)


def bundled_vehicles() -> tuple[Path, ...]:
    """The bundled vehicle files: the sports car and the SUV."""
    sports = example_vehicle_path()
    return (sports, sports.parent / "suv.toml")


def scenario_signals(name: str, seed: int = 0, vehicle_path: Path | None = None) -> Signals:
    """The measured log of a bundled scenario (``seed``: road, sensors); default: sports car."""
    path = example_vehicle_path() if vehicle_path is None else vehicle_path
    result = run_scenario(name, path, options=Options(seed=seed))
    return signals_from_frame(result.log, source=name)


def pooled_rmse(loads: np.ndarray, reference: np.ndarray) -> float:
    """Pooled RMSE over the four wheels [N] (Siegloff & Choi eq. 26, all wheels)."""
    return float(wheel_metrics(loads, reference).loc["pooled", "RMSE"])


def detection_delay(faults: pd.DataFrame, channel: str, onset: float) -> float:
    """Seconds from ``onset`` to the first isolation of ``channel`` at or after it (NaN: none)."""
    hits = faults[(faults["channel"] == channel) & (faults["end"] >= onset)]
    return float(max(hits["start"].min() - onset, 0.0)) if len(hits) else float("nan")


def vehicle_guards(vehicle, overrides: dict[str, float] | None = None) -> GuardSettings:
    """The vehicle's guard settings (``[filter.faults]``) with ``overrides`` by name."""
    return dataclasses.replace(guard_settings_for(vehicle), **(overrides or {}))


def fault_table(
    scenarios=FAULT_SCENARIOS,
    seed: int = 0,
    vehicle_path: Path | None = None,
    overrides: dict[str, float] | None = None,
) -> pd.DataFrame:
    """One row per scenario and fault: RMSE before and after, delay, isolations."""
    path = example_vehicle_path() if vehicle_path is None else vehicle_path
    vehicle = load_vehicle(path)
    guarded = build("kf", vehicle, guard_settings=vehicle_guards(vehicle, overrides))
    unguarded = build("kf", vehicle, guard_settings=GUARDS_OFF)
    rows = []
    for scenario in scenarios:
        clean = scenario_signals(scenario, seed, path)
        k = int(ONSET * len(clean))
        for fault in FAULTS:
            rng = np.random.default_rng(seed)
            signals = fault.inject(clean, k, rng)
            after = guarded.run(signals)
            before = unguarded.run(signals)
            channels = sorted(set(after.faults["channel"]))
            rows.append(
                {
                    "vehicle": vehicle.name,
                    "scenario": scenario,
                    "fault": fault.name,
                    "rmse_before": pooled_rmse(before.loads, signals.reference),
                    "rmse_after": pooled_rmse(after.loads, signals.reference),
                    "delay_s": (
                        detection_delay(after.faults, fault.channel, clean.t[k])
                        if fault.channel
                        else float("nan")
                    ),
                    "isolated": ",".join(channels) if channels else "-",
                    "flagged_samples": int(np.count_nonzero(after.flags >> 8)),
                }
            )
    return pd.DataFrame(rows)


#: Fault limits of the calibration run: every isolated parity fault is reported.
_TINY_LIMITS = {
    "travel_fault": 1e-9,
    "ax_fault": 1e-9,
    "ay_fault": 1e-9,
    "az_fault": 1e-9,
    "parity_spread_factor": 1e-12,
}


#: Vehicle models of the false-alarm run: the file's own, the paper's (every term off).
MODELS = {"full": lambda vehicle: vehicle, "paper": paper_model}


def false_alarms(
    scenarios=tuple(SCENARIOS),
    seeds=(0,),
    vehicle_paths: tuple[Path, ...] | None = None,
    overrides: dict[str, float] | None = None,
    models: tuple[str, ...] = ("full",),
    progress: Callable[[pd.DataFrame], None] | None = None,
) -> pd.DataFrame:
    """Fault-monitor isolations and clean-log RMSE (guards on and off) per vehicle, seed,
    scenario and model (:data:`MODELS`; each log is simulated once for every model).

    ``floor_<channel>``: the largest fault the parity test attributes to the
    channel (one channel explaining ``isolation_fraction`` of the residual for
    ``fault_confirm_time``) on the clean log [m, m/s^2]: the vehicle's
    ``[filter.faults]`` limits must lie above it. ``progress(rows)`` is called
    with the rows so far after each vehicle and seed.
    """
    rows = []
    for path in bundled_vehicles() if vehicle_paths is None else vehicle_paths:
        base = load_vehicle(path)
        filters = {}
        for model in models:
            vehicle = MODELS[model](base)
            kf = build("kf", vehicle, guard_settings=vehicle_guards(base, overrides))
            plain = build("kf", vehicle, guard_settings=GUARDS_OFF)
            probe = build(
                "kf", vehicle, guard_settings=dataclasses.replace(kf.guard_settings, **_TINY_LIMITS)
            )
            filters[model] = (kf, plain, probe)
        for seed in seeds:
            for scenario in scenarios:
                signals = scenario_signals(scenario, seed, path)
                for model, (kf, plain, probe) in filters.items():
                    rows.append(_alarm_row(kf, plain, probe, signals, scenario, seed, model))
            if progress is not None:
                progress(pd.DataFrame(rows))
    return pd.DataFrame(rows)


def _alarm_row(kf, plain, probe, signals: Signals, scenario: str, seed: int, model: str) -> dict:
    """One row of :func:`false_alarms`: one clean log through one vehicle model."""
    estimate = kf.run(signals)
    floors = probe.run(signals).faults
    row = {
        "vehicle": kf.vehicle.name,
        "model": model,
        "scenario": scenario,
        "seed": seed,
        "duration_s": float(signals.t[-1] - signals.t[0]),
        "alarms": len(estimate.faults),
        "channels": ",".join(estimate.faults["channel"]) or "-",
        "rmse_guarded": pooled_rmse(estimate.loads, signals.reference),
        "rmse_plain": pooled_rmse(plain.run(signals).loads, signals.reference),
    }
    for channel in FAULT_CHANNELS:
        peaks = floors["statistic"][floors["channel"] == channel]
        row[f"floor_{channel}"] = float(peaks.max()) * 1e-9 if len(peaks) else 0.0
    return row


def alarm_bound(count: int, hours: float) -> float:
    r"""Exact one-sided 95 % Poisson upper bound on the alarm rate [1/h].

    :math:`\chi^2_{0.95}(2 (n + 1)) / (2 T)` for ``count`` alarms in ``hours``; with
    no alarm, :math:`3.0 / T`: 3.0 h of clean driving bound the rate below 1 per hour.
    """
    return float(chi2.ppf(0.95, 2 * (count + 1)) / 2 / hours)


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("faults")
    parser.add_argument(
        "--quick", action="store_true", help="iso-dlc and brake-in-turn only, no laps"
    )
    parser.add_argument(
        "--seeds",
        type=int,
        default=1,
        help="clean logs simulated with this many seeds for the false alarms (default 1)",
    )
    parser.add_argument(
        "--alarms-only",
        action="store_true",
        help="only the false alarms on the clean logs (every scenario, both bundled vehicles)",
    )
    parser.add_argument(
        "--vehicle",
        type=Path,
        action="append",
        help="vehicle file (repeatable; default: the bundled sports car and SUV)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a guard setting for every vehicle (repeatable), e.g. travel_fault=0.002",
    )
    parser.add_argument(
        "--model",
        choices=("full", "paper", "both"),
        default="full",
        help="vehicle model of the false alarms and spikes: the file's, the paper's "
        "(every [model] term off) or both on the same logs (default full)",
    )
    parser.add_argument(
        "--progress",
        action="store_true",
        help="print the hours and alarms so far after each vehicle and seed",
    )
    parser.add_argument(
        "--spikes",
        action="store_true",
        help="only the isolation table of one spike on each channel (at rest and iso-dlc)",
    )
    parser.set_defaults(handler=run)


def alarm_summary(alarms: pd.DataFrame) -> str:
    """Hours of clean driving, alarms and the 95 % upper bound, per model and in all."""
    lines = []
    groups = [(f"model {m}", g) for m, g in alarms.groupby("model", sort=False)]
    for name, group in [*groups, ("both models", alarms)] if len(groups) > 1 else groups:
        hours = group["duration_s"].sum() / 3600.0
        count = int(group["alarms"].sum())
        lines.append(
            f"{name}: {count} alarms in {hours:.2f} h of clean driving "
            f"({group['vehicle'].nunique()} vehicles, {group['seed'].nunique()} seeds): "
            f"{count / hours:.2f} per hour (95 % upper bound {alarm_bound(count, hours):.2f})"
        )
    return "\n".join(lines)


def _print_alarms(alarms: pd.DataFrame) -> None:
    print("\nFalse alarms of the fault monitor on the clean logs:")
    shown = alarms.drop(columns=[c for c in alarms if c.startswith("floor_")])
    print(shown.to_string(index=False, float_format=lambda x: f"{x:.1f}"))
    print(alarm_summary(alarms))
    print("\nClean-log RMSE pooled over the logs [N] and the largest isolated parity fault:")
    for (name, model), group in alarms.groupby(["vehicle", "model"], sort=False):
        weights = group["duration_s"]
        guarded = np.sqrt(np.average(group["rmse_guarded"] ** 2, weights=weights))
        plain = np.sqrt(np.average(group["rmse_plain"] ** 2, weights=weights))
        floors = ", ".join(f"{c} {group[f'floor_{c}'].max():.4g}" for c in FAULT_CHANNELS)
        print(f"{name} ({model}): guarded {guarded:.1f} N, plain {plain:.1f} N; floor: {floors}")


def _progress_line(rows: pd.DataFrame) -> str:
    last = rows.iloc[-1]
    return f"[{last['vehicle']} seed {last['seed']}] " + alarm_summary(rows).replace("\n", "; ")


def _print_spikes(paths, overrides, models) -> None:
    print("Single spike at mid-log on each channel: isolated channels (the spiked one or none),")
    print("time isolated [s], pooled RMSE change [N] (guarded, spiked minus clean):")
    tables = []
    for path in paths:
        base = load_vehicle(path)
        for model in models:
            kf = build("kf", MODELS[model](base), guard_settings=vehicle_guards(base, overrides))
            for scenario in SPIKE_SCENARIOS:
                table = spike_table(kf, scenario_signals(scenario, 0, path), scenario, pooled_rmse)
                tables.append(table.assign(model=model))
    table = pd.concat(tables)
    print(table.to_string(index=False, float_format=lambda x: f"{x:.2f}"))
    wrong = table[table["healthy_isolated"] != "-"]
    print(f"spikes that isolated a healthy channel: {len(wrong)} of {len(table)}")


def parse_overrides(items: list[str]) -> dict[str, float]:
    """``NAME=VALUE`` guard-setting overrides; an error names the item and the settings."""
    overrides = {}
    for item in items:
        name, _, value = item.partition("=")
        if name not in GuardSettings.names():
            names = ", ".join(GuardSettings.names())
            raise ValueError(f"--set {item}: unknown guard setting; choose from {names}")
        try:
            overrides[name] = float(value)
        except ValueError:
            raise ValueError(f"--set {item}: the value must be a number") from None
    GuardSettings(**overrides)  # ranges checked here, with the setting named
    return overrides


def run(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    try:
        overrides = parse_overrides(args.set)
    except ValueError as error:
        print(f"error: {error}")
        return 2
    paths = tuple(args.vehicle) if args.vehicle else bundled_vehicles()
    models = ("full", "paper") if args.model == "both" else (args.model,)
    if args.spikes:
        _print_spikes(paths, overrides, models)
        print(f"({time.perf_counter() - start:.0f} s)")
        return 0
    if not args.alarms_only:
        scenarios = ("iso-dlc", "brake-in-turn") if args.quick else FAULT_SCENARIOS
        table = pd.concat(
            [fault_table(scenarios, vehicle_path=path, overrides=overrides) for path in paths]
        )
        print("Fault injection (faults from 20 % of each log; RMSE pooled over the wheels):")
        table["delay_s"] = [f"{x:.2f}" if np.isfinite(x) else "-" for x in table["delay_s"]]
        print(table.to_string(index=False, float_format=lambda x: f"{x:.1f}"))
    clean = ("iso-dlc", "brake-in-turn", "wheel-lift") if args.quick else tuple(SCENARIOS)
    progress = (lambda rows: print(_progress_line(rows), flush=True)) if args.progress else None
    alarms = false_alarms(clean, tuple(range(args.seeds)), paths, overrides, models, progress)
    _print_alarms(alarms)
    print(f"({time.perf_counter() - start:.0f} s)")
    return 0
