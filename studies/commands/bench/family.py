"""``wheelload bench family``: each registered method's ``run`` over a log, against the KF's.

Every method of ``--methods`` (default: every registered one) is built through
the registry (:func:`wheelload.estimators.registry.build`), run once on the
whole log untimed (which builds or loads its compiled loop), then timed over
``--repeats`` alternating rounds: in each round every method runs the log once,
in turn, so that all meet the same machine load. A method's figure is its wall
time per sample in µs, min / median / max over the rounds, and its time over the
two-stage KF's (``kf``, always timed) in the same round, min / median / max.
The family methods run on the vehicle model(s) of ``--suspension``
(:class:`~wheelload.estimators.SuspensionModel`); ``both`` times each on
either. The load average (1 min) is printed at the start and the end.

Printed, never asserted.

Example
-------
``wheelload bench family --repeats 5 --suspension both``
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators import DEFAULT_MODEL, SuspensionModel
from wheelload.estimators.protocol import Estimator
from wheelload.estimators.registry import build, method, methods
from wheelload.estimators.types import Signals
from wheelload.studies.commands.options import add_allow_unusual

REFERENCE = "kf"
BOTH = "both"


def register_bench(subparsers: argparse._SubParsersAction) -> None:
    """``wheelload bench family``."""
    parser = subparsers.add_parser("family")
    parser.add_argument("--log", help="log with the usual channels (default: the bundled example)")
    parser.add_argument(
        "--vehicle", help="vehicle TOML file (default: bundled sports car, the example's)"
    )
    parser.add_argument(
        "--methods", help="comma-separated method names (default: every registered method)"
    )
    parser.add_argument("--repeats", type=int, default=5, help="alternating rounds (default 5)")
    parser.add_argument(
        "--suspension",
        choices=[*(m.value for m in SuspensionModel), BOTH],
        default=DEFAULT_MODEL.value,
        help="vehicle model of the family methods: full (default), paper, or both "
        "(each family method timed on either)",
    )
    add_allow_unusual(parser)
    parser.set_defaults(handler=run)


@dataclass(frozen=True, kw_only=True)
class Entry:
    """One timed estimator: its method name, its vehicle model (None: no choice)."""

    name: str
    model: SuspensionModel | None
    estimator: Estimator

    @property
    def label(self) -> str:
        return "-" if self.model is None else self.model.value


def models_of(choice: str) -> tuple[SuspensionModel, ...]:
    """The vehicle models of ``--suspension`` (``both``: full, then paper)."""
    if choice == BOTH:
        return (SuspensionModel.FULL, SuspensionModel.PAPER)
    return (SuspensionModel.parse(choice),)


def method_names(text: str | None) -> tuple[str, ...]:
    """``--methods`` in canonical spelling, ``kf`` first (added if missing)."""
    from wheelload.studies.pipeline.comparison import parse_methods

    names = tuple(methods()) if text is None else parse_methods(text)
    return (REFERENCE, *(name for name in names if name != REFERENCE))


def entries(names: tuple[str, ...], vehicle, models: tuple[SuspensionModel, ...]) -> list[Entry]:
    """One entry per method and model (a method without the choice: one entry)."""
    out = []
    for name in names:
        if not method(name).model_choice:
            out.append(Entry(name=name, model=None, estimator=build(name, vehicle)))
            continue
        for model in models:
            out.append(Entry(name=name, model=model, estimator=build(name, vehicle, model)))
    return out


def time_rounds(entries: list[Entry], signals: Signals, repeats: int) -> list[list[float]]:
    """Seconds per sample of each entry's ``run``, per round (rows: entries)."""
    for entry in entries:
        entry.estimator.run(signals)  # build or load the compiled loop, warm the caches
    seconds: list[list[float]] = [[] for _ in entries]
    for _ in range(repeats):
        for row, entry in zip(seconds, entries):
            gc.collect()
            start = time.perf_counter()
            entry.estimator.run(signals)
            row.append((time.perf_counter() - start) / len(signals))
    return seconds


def spread(values: list[float], digits: int) -> str:
    """``min / median / max`` with ``digits`` decimals."""
    low, mid, high = min(values), statistics.median(values), max(values)
    return f"{low:.{digits}f} / {mid:.{digits}f} / {high:.{digits}f}"


def load_average() -> str:
    """The 1, 5 and 15 min load averages (``uptime``)."""
    return " ".join(f"{value:.2f}" for value in os.getloadavg())


def run(args: argparse.Namespace) -> int:
    from wheelload.estimators import read_log
    from wheelload.models import example_vehicle_path, load_vehicle
    from wheelload.studies.pipeline.example_log import example_log_path

    if args.repeats < 1:
        raise ValueError(f"--repeats must be >= 1, got {args.repeats}")
    names = method_names(args.methods)
    log_path = Path(args.log) if args.log else example_log_path()
    vehicle = load_vehicle(args.vehicle or example_vehicle_path(), allow_unusual=args.allow_unusual)
    signals = read_log(log_path)
    print(
        f"wheelload bench family: {log_path.name}, {len(signals)} samples, {vehicle.name}; "
        f"{args.repeats} alternating rounds, family methods on --suspension {args.suspension}"
    )
    print(f"load average at start: {load_average()}")
    timed = entries(names, vehicle, models_of(args.suspension))
    seconds = time_rounds(timed, signals, args.repeats)
    reference = seconds[0]  # kf, first by method_names
    width = max(len(entry.name) for entry in timed)
    print(
        f"{'method':<{width}}  model  {'us/sample min / median / max':>32}  x kf min / median / max"
    )
    for entry, row in zip(timed, seconds):
        micro = [1e6 * s for s in row]
        ratio = [s / kf for s, kf in zip(row, reference)]
        print(
            f"{entry.name:<{width}}  {entry.label:<5}  {spread(micro, 3):>32}  {spread(ratio, 3)}"
        )
    print(f"load average at end:   {load_average()}")
    return 0
