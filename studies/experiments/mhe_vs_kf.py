"""Study ``mhe-vs-kf``: accuracy against time per sample of the KF, projection KF and MHE.

Estimators: the two-stage KF, the projection KF with :math:`W = P^{-1}` and
:math:`W = I`, and the MHE with soft and hard equilibrium, with and without
the bounds :math:`0 \\le F_z`, for each window length, all with the Kalman
arrival cost; and the soft, unbounded MHE with the steady-state arrival cost.
Errors are pooled over all wheels, samples and logs (Siegloff & Choi eq.
31-34, via :func:`wheelload.studies.metrics.pooled_metrics`).

Time per sample: the MHE's own wall time of each QP update and solve; for
the filters, the wall time of the per-sample :meth:`step` call on the first
``timing_samples`` samples of each log (their whole-log ``run`` is a compiled
loop, reported separately as ``run us``).

:func:`robust_sweep` compares instead what a filter cannot do: robust
losses, bias states and lagged output of the MHE, and the KF's offline RTS
smoother, on clean and faulted logs (:mod:`wheelload.studies.experiments.faults.sensor_faults`).

Example
-------
>>> table = mhe_vs_kf([read_log("iso-dlc.csv")], load_vehicle(example_vehicle_path()))
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators import (
    GUARDS_OFF,
    Arrival,
    BiasStates,
    Constraint,
    Loss,
    MheSettings,
    ResidualLoss,
    Sample,
    Signals,
)
from wheelload.estimators.protocol import Estimator, sample_intervals
from wheelload.estimators.registry import build
from wheelload.models import Vehicle
from wheelload.studies.experiments.faults.sensor_faults import inject
from wheelload.studies.experiments.runs.choices import HORIZONS, Fault
from wheelload.studies.metrics import pooled_metrics


@dataclass(frozen=True, kw_only=True)
class StudySettings:
    horizons: tuple[int, ...] = HORIZONS
    timing_samples: int = 2000  # per log, for the filters' per-sample step timing


def estimators(vehicle: Vehicle, horizons: tuple[int, ...]) -> list:
    """The compared estimators, filters first."""
    family = [
        build("kf", vehicle),
        build("projection-mp", vehicle),
        build("projection-ls", vehicle),
    ]
    for constraint in Constraint:
        for bounded in (False, True):
            for horizon in horizons:
                settings = MheSettings(horizon=horizon, constraint=constraint, bounded=bounded)
                family.append(build("mhe", vehicle, settings=settings))
    # With the exact Kalman arrival cost an unbounded window adds nothing to the
    # filter; with the steady-state arrival the window length matters.
    for horizon in horizons:
        settings = MheSettings(horizon=horizon, arrival=Arrival.STEADY_STATE)
        family.append(build("mhe", vehicle, settings=settings))
    return family


def step_times(kf: Estimator, signals: Signals, samples: int) -> np.ndarray:
    """Wall time [s] of each per-sample ``step`` call of a filter on the first samples."""
    n = min(samples, len(signals))
    dt = sample_intervals(signals.t)
    state = kf.initial_state()
    times = np.empty(n)
    for k in range(n):
        sample = Sample(d=signals.d[k], v=signals.v[k], acc=signals.acc[k], vx=float(signals.vx[k]))
        start = time.perf_counter()
        state, _ = kf.step(state, sample, float(dt[k]))
        times[k] = time.perf_counter() - start
    return times


def mhe_vs_kf(
    logs: list[Signals], vehicle: Vehicle, settings: StudySettings = StudySettings()
) -> pd.DataFrame:
    """One row per estimator: pooled RMSE, P95, Max [N], minimum load [N], times [us]."""
    for signals in logs:
        if signals.reference is None:
            raise ValueError(f"{signals.source}: the log has no reference loads (fz_* columns)")
    reference = np.vstack([signals.reference for signals in logs])
    rows = []
    for estimator in estimators(vehicle, settings.horizons):
        loads, times, run_time, fallback = [], [], 0.0, 0
        for signals in logs:
            start = time.perf_counter()
            estimate = estimator.run(signals)
            run_time += time.perf_counter() - start
            loads.append(estimate.loads)
            if getattr(estimate, "solve_time", None) is not None:  # the MHE's own QP times
                times.append(estimate.solve_time)
                fallback += int(estimate.fallback.sum())
            else:
                times.append(step_times(estimator, signals, settings.timing_samples))
        loads = np.vstack(loads)
        times = np.concatenate(times) * 1e6
        metrics = pooled_metrics(loads, reference)
        rows.append(
            {
                "estimator": estimator.name,
                "RMSE": metrics["RMSE"],
                "P95": metrics["P95"],
                "Max": metrics["Max"],
                "min load": float(loads.min()),
                "median us": float(np.median(times)),
                "p99 us": float(np.percentile(times, 99)),
                "run us": 1e6 * run_time / len(reference),
                "fallback": fallback,
            }
        )
    return pd.DataFrame(rows).set_index("estimator")


def plot_accuracy_against_time(table: pd.DataFrame, path: str | Path) -> Path:
    """Pooled RMSE and minimum estimated load against median time per sample."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5), sharex=True)
    groups = {
        "filters": (~table.index.str.startswith("MHE"), "s", (4, 6)),
        "MHE soft": (table.index.str.contains(r"\(soft\)"), "o-", (3, 5)),
        "MHE soft, bounded": (table.index.str.contains("soft, bounded"), "o--", (3, -11)),
        "MHE soft, steady arrival": (table.index.str.contains("steady arrival"), "D:", (3, 5)),
        "MHE hard": (table.index.str.contains(r"\(hard\)"), "^-", (3, 5)),
        "MHE hard, bounded": (table.index.str.contains("hard, bounded"), "^--", (3, -11)),
    }
    for column, ax in zip(("RMSE", "min load"), axes):
        for label, (rows, style, offset) in groups.items():
            part = table[rows]
            ax.plot(part["median us"], part[column], style, label=label, alpha=0.85)
            for i, (name, row) in enumerate(part.iterrows()):
                short = name.split(" (")[0].replace("MHE ", "")
                if label == "filters":
                    short = name
                    offset = (4, 6 - 12 * i)
                ax.annotate(short, (row["median us"], row[column]), fontsize=7,
                            xytext=offset, textcoords="offset points")  # fmt: skip
        ax.set_xscale("log")
        ax.set_xlabel("median time per sample [us], Python")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("pooled RMSE [N]")
    axes[1].set_ylabel("minimum estimated load [N]")
    axes[1].axhline(0.0, color="black", lw=0.8)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


# -- the sweep of the settings a filter cannot have -----------------------------------------


@dataclass(frozen=True, kw_only=True)
class Candidate:
    """One row of the robust sweep: a name and how it estimates a log."""

    name: str
    settings: MheSettings | None  # None: a filter (see ``offline``, ``guards``)
    offline: bool = False  # filter only: the RTS smoother instead of the filter
    guards: bool = True  # filter only: False for the plain KF (GUARDS_OFF)


PLAIN_KF = "two-stage KF, no guards"

#: Huber at 0.5σ on the suspension rows: leaves this plant's model residuals (0.1-0.2σ)
#: quadratic and discounts faults.
SUSPENSION_HUBER = ResidualLoss(kind=Loss.HUBER, threshold=0.5)
#: Huber at 0.2σ: discounts more of both.
TIGHT_HUBER = ResidualLoss(kind=Loss.HUBER, threshold=0.2)


def robust_candidates(horizon: int = 10, quick: bool = False) -> list[Candidate]:
    """The KF with and without its guards, its RTS smoother, and the MHE settings a KF lacks.

    Huber 0.5σ on the suspension rows (:data:`SUSPENSION_HUBER`), 0.2σ
    (:data:`TIGHT_HUBER`), L1.
    """
    huber, tight, l1 = SUSPENSION_HUBER, TIGHT_HUBER, ResidualLoss(kind=Loss.L1)
    lag = min(5, horizon - 1)
    rows = [
        Candidate(name="two-stage KF", settings=None),
        Candidate(name=PLAIN_KF, settings=None, guards=False),
        Candidate(name="two-stage KF + RTS (offline)", settings=None, offline=True),
        Candidate(
            name=f"MHE N={horizon} lag {lag}", settings=MheSettings(horizon=horizon, lag=lag)
        ),
        Candidate(
            name=f"MHE N={horizon} Huber 0.5σ (susp)",
            settings=MheSettings(horizon=horizon, suspension_loss=huber),
        ),
    ]
    if quick:
        return rows
    return rows + [
        Candidate(name=f"MHE N={horizon} quadratic", settings=MheSettings(horizon=horizon)),
        Candidate(
            name=f"MHE N={horizon} Huber 0.2σ (susp)",
            settings=MheSettings(horizon=horizon, suspension_loss=tight),
        ),
        Candidate(
            name=f"MHE N={horizon} Huber 0.2σ (susp+eq)",
            settings=MheSettings(horizon=horizon, suspension_loss=tight, constraint_loss=tight),
        ),
        Candidate(
            name=f"MHE N={horizon} L1 (susp)",
            settings=MheSettings(horizon=horizon, suspension_loss=l1),
        ),
        Candidate(
            name=f"MHE N={horizon} travel offsets",
            settings=MheSettings(horizon=horizon, bias_states=BiasStates.TRAVEL),
        ),
        Candidate(
            name=f"MHE N={horizon} ax/ay biases",
            settings=MheSettings(horizon=horizon, bias_states=BiasStates.ACCELERATION),
        ),
        Candidate(
            name=f"MHE N={horizon} Huber 0.2σ (susp) + ride heights + ay bias",
            settings=MheSettings(
                horizon=horizon,
                suspension_loss=tight,
                bias_states=BiasStates.RIDE_HEIGHT | BiasStates.LATERAL,
            ),
        ),
        Candidate(
            name=f"MHE N={horizon} Huber 0.2σ (susp) + travel offsets",
            settings=MheSettings(
                horizon=horizon, suspension_loss=tight, bias_states=BiasStates.TRAVEL
            ),
        ),
    ]


def robust_sweep(
    logs: list[Signals],
    vehicle: Vehicle,
    faults: tuple[Fault, ...] = tuple(Fault),
    candidates: list[Candidate] | None = None,
) -> pd.DataFrame:
    """Pooled RMSE [N] of each candidate on each fault (columns), over all logs.

    Each log is faulted by :func:`wheelload.studies.experiments.faults.sensor_faults.inject`; the
    reference loads stay those of the clean log. Also: the MHE's median time
    per sample [us] and its fallbacks, summed over faults.
    """
    for signals in logs:
        if signals.reference is None:
            raise ValueError(f"{signals.source}: the log has no reference loads (fz_* columns)")
    candidates = candidates or robust_candidates()
    reference = np.vstack([signals.reference for signals in logs])
    filters = {True: build("kf", vehicle), False: build("kf", vehicle, guard_settings=GUARDS_OFF)}
    rows = []
    for candidate in candidates:
        kf = filters[candidate.guards]
        mhe = build("mhe", vehicle, settings=candidate.settings) if candidate.settings else None
        row: dict = {"estimator": candidate.name}
        times, fallback = [], 0
        for fault in faults:
            loads = []
            for signals in logs:
                faulty = inject(signals, fault)
                if mhe is None:
                    estimate = kf.smooth(faulty) if candidate.offline else kf.run(faulty)
                else:
                    estimate = mhe.run(faulty)
                    times.append(estimate.solve_time)
                    fallback += int(estimate.fallback.sum())
                loads.append(estimate.loads)
            row[fault.value] = pooled_metrics(np.vstack(loads), reference)["RMSE"]
        row["median us"] = float(np.median(np.concatenate(times)) * 1e6) if times else np.nan
        row["fallback"] = fallback
        rows.append(row)
    return pd.DataFrame(rows).set_index("estimator")


def against_kf(
    table: pd.DataFrame, faults: tuple[Fault, ...], reference: str = "two-stage KF"
) -> pd.DataFrame:
    """Each RMSE as a percentage change against ``reference``'s on the same fault."""
    columns = [fault.value for fault in faults]
    kf = table.loc[reference, columns]
    return (100.0 * (table[columns] / kf - 1.0)).round(1)
