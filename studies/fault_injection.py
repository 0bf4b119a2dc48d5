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
``--seeds N``: the clean logs with N seeds of road and sensors).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import chi2

from wheelload.estimators import Signals, TwoStageKF
from wheelload.estimators.guard import GUARDS_OFF
from wheelload.estimators.signals import signals_from_frame
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.studies.metrics import wheel_metrics
from wheelload.studies.scenario_runner import run_scenario
from wheelload.studies.scenarios import SCENARIOS, Options

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


def scenario_signals(name: str, seed: int = 0) -> Signals:
    """The measured log of a bundled scenario with the bundled vehicle (``seed``: road, sensors)."""
    result = run_scenario(name, example_vehicle_path(), options=Options(seed=seed))
    return signals_from_frame(result.log, source=name)


def pooled_rmse(loads: np.ndarray, reference: np.ndarray) -> float:
    """Pooled RMSE over the four wheels [N] (Siegloff & Choi eq. 26, all wheels)."""
    return float(wheel_metrics(loads, reference).loc["pooled", "RMSE"])


def detection_delay(faults: pd.DataFrame, channel: str, onset: float) -> float:
    """Seconds from ``onset`` to the first isolation of ``channel`` at or after it (NaN: none)."""
    hits = faults[(faults["channel"] == channel) & (faults["end"] >= onset)]
    return float(max(hits["start"].min() - onset, 0.0)) if len(hits) else float("nan")


def fault_table(scenarios=FAULT_SCENARIOS, seed: int = 0) -> pd.DataFrame:
    """One row per scenario and fault: RMSE before and after, delay, isolations."""
    vehicle = load_vehicle(example_vehicle_path())
    guarded, unguarded = TwoStageKF(vehicle), TwoStageKF(vehicle, guard_settings=GUARDS_OFF)
    rows = []
    for scenario in scenarios:
        clean = scenario_signals(scenario)
        k = int(ONSET * len(clean))
        for fault in FAULTS:
            rng = np.random.default_rng(seed)
            signals = fault.inject(clean, k, rng)
            after = guarded.run(signals)
            before = unguarded.run(signals)
            channels = sorted(set(after.faults["channel"]))
            rows.append(
                {
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


def false_alarms(scenarios=tuple(SCENARIOS), seeds=(0,)) -> pd.DataFrame:
    """Fault-monitor isolations on the clean log of each scenario and seed."""
    vehicle = load_vehicle(example_vehicle_path())
    kf = TwoStageKF(vehicle)
    rows = []
    for seed in seeds:
        for scenario in scenarios:
            signals = scenario_signals(scenario, seed)
            estimate = kf.run(signals)
            rows.append(
                {
                    "scenario": scenario,
                    "seed": seed,
                    "duration_s": float(signals.t[-1] - signals.t[0]),
                    "alarms": len(estimate.faults),
                    "channels": ",".join(estimate.faults["channel"]) or "-",
                }
            )
    return pd.DataFrame(rows)


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "faults", help="fault-injection table: RMSE with and without the guards, delays"
    )
    parser.add_argument(
        "--quick", action="store_true", help="iso-dlc and brake-in-turn only, no laps"
    )
    parser.add_argument(
        "--seeds",
        type=int,
        default=1,
        help="clean logs simulated with this many seeds for the false alarms (default 1)",
    )
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    scenarios = ("iso-dlc", "brake-in-turn") if args.quick else FAULT_SCENARIOS
    table = fault_table(scenarios)
    print("Fault injection (faults from 20 % of each log; RMSE pooled over the wheels):")
    table["delay_s"] = [f"{x:.2f}" if np.isfinite(x) else "-" for x in table["delay_s"]]
    print(table.to_string(index=False, float_format=lambda x: f"{x:.1f}"))
    clean = ("iso-dlc", "brake-in-turn", "wheel-lift") if args.quick else tuple(SCENARIOS)
    alarms = false_alarms(clean, tuple(range(args.seeds)))
    hours = alarms["duration_s"].sum() / 3600.0
    count = int(alarms["alarms"].sum())
    print("\nFalse alarms of the fault monitor on the clean logs:")
    print(alarms.to_string(index=False, float_format=lambda x: f"{x:.1f}"))
    # Exact one-sided 95 % Poisson bound on the rate: chi^2_{0.95}(2 (count + 1)) / 2.
    bound = chi2.ppf(0.95, 2 * (count + 1)) / 2 / hours
    print(
        f"total {count} in {hours * 60:.1f} min: {count / hours:.2f} per hour "
        f"(95 % upper bound {bound:.1f} per hour)"
    )
    print(f"({time.perf_counter() - start:.0f} s)")
    return 0
