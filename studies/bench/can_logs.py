"""The KF on a CAN car's logs: ``wheelload bench can``.

The bundled car's ISO lane change, simulated at 200 Hz, is the synchronous
log. It is re-sampled as the CAN car of ``studies/data/can_car.dbc`` sends it
(:mod:`~wheelload.studies.drive.can_car`: IMU 200 Hz, travel 100 Hz, wheel speeds
50 Hz, 5-20 ms frame latencies, jitter) and written as MDF4 bus logging and as
BLF, then read through a channel map with and without the frames' ``latency``
keys, and once more with ``ay`` delayed by ``--delay`` seconds inside the IMU
(a filter nothing declares): the wiring checks' lag of ``ay``, and the RMSE with
that lag added to ``ay``'s latency key. The CAN car's maps put the channels on an
even 200 Hz clock (``[clock] rate = 200``); ``STEM.stamps.toml`` on the IMU frame's
own stamps instead, which a jitter of :data:`ROUGH_JITTER` (``rough``) makes too
uneven for the filter's differentiators; ``STEM.union.toml`` on the union of every
channel's stamps (``[clock] union = true``: each travel's rate derived on its own stamps,
each row filtered at its own time stamp as the timed filter does), read from the jittered
log and from one without jitter (``still``), whose shifted stamps fall on the IMU's 5 ms
grid. Each
RMSE is the KF's, pooled over the four wheels, against the plant's reference loads at
the log's own time stamps, and is printed with its ratio to the synchronous log's.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators import LogError, read_log
from wheelload.estimators.registry import build
from wheelload.models.conventions import WHEELS
from wheelload.models.vehicle.file import example_vehicle_path, load_vehicle
from wheelload.studies.drive.can_car import UNION_CLOCK, CanCar, channel_map_text, write_can_logs
from wheelload.studies.drive.scenario_runner import run_scenario

RATE = 200.0  # Hz, the synchronous log
ROUGH_JITTER = 200e-6  # s, a logger whose stamps jitter as much as a busy bus delays frames
REFERENCE = [f"fz_{w}" for w in WHEELS]


@dataclass(frozen=True, kw_only=True)
class CanScore:
    """One log read through one channel map: the KF's RMSE, or why it did not run."""

    log: str
    channel_map: str
    rmse: float  # N, NaN when the log was refused
    ratio: float  # to the synchronous log's RMSE
    note: str = ""


def _rmse(kf, path: Path, channels: Path | None, truth: pd.DataFrame) -> tuple[float, str]:
    """The KF's pooled RMSE against ``truth``'s loads at the log's own stamps."""
    try:
        signals = read_log(path, channels=channels, wiring_checks=False)
    except LogError as error:
        return float("nan"), str(error)
    loads = np.asarray(kf.run(signals).loads)
    t = truth["t"].to_numpy(float)
    reference = np.column_stack([np.interp(signals.t, t, truth[c]) for c in REFERENCE])
    return float(np.sqrt(np.mean((loads - reference) ** 2))), ""


def ay_lag(path: Path, channels: Path) -> tuple[float, float, str]:
    """``(lag, standard error, the wiring checks' note)`` of ``ay`` in a CAN log."""
    from wheelload.estimators.logs.checks import check_wiring

    signals = read_log(path, channels=channels, wiring_checks=False)
    report = check_wiring(signals.t, signals.vx, signals.acc, signals.d, signals.rates,
                          own_clocks=signals.own_clocks)  # fmt: skip
    (check,) = [c for c in report.checks if c.name.startswith("ay lag")]
    std = re.search(r"\+- ([0-9.]+) s", check.note)
    return check.statistic, float(std.group(1)) if std else float("nan"), check.note


def with_latency(text: str, channel: str, extra: float) -> str:
    """A channel map's TOML with ``extra`` seconds added to ``channel``'s latency key."""
    pattern = re.compile(rf"(\[channels\.{channel}\]\n(?:[^\[\n][^\n]*\n)*?latency = )([0-9.e-]+)")
    if not pattern.search(text):
        raise ValueError(f"the channel map has no latency key for '{channel}'")
    return pattern.sub(lambda m: f"{m.group(1)}{float(m.group(2)) + extra:.6g}", text, count=1)


def can_study(folder: Path, delay: float = 0.3, seed: int = 0) -> tuple[list[CanScore], float]:
    """The scores of module docstring, and the lag found for ``ay`` [s]."""
    vehicle = load_vehicle(example_vehicle_path())
    kf = build("kf", vehicle)
    truth = run_scenario("iso-dlc", example_vehicle_path(), output_rate=RATE).log
    sync = folder / "sync.csv"
    truth.to_csv(sync, index=False, float_format="%.17g")
    base, _ = _rmse(kf, sync, None, truth)
    rows = [CanScore(log="sync.csv", channel_map="-", rmse=base, ratio=1.0)]
    radius = (vehicle.tyres.radius_front, vehicle.tyres.radius_rear)
    car = CanCar(seed=seed, wheel_radius=radius)
    cars = {"can": car, "late": dataclasses.replace(car, signal_delays={"ay": delay}),
            "still": dataclasses.replace(car, jitter=0.0),
            "rough": dataclasses.replace(car, jitter=ROUGH_JITTER)}  # fmt: skip
    for stem, car in cars.items():
        write_can_logs(truth, folder, stem, car, replace=True)
    for stem, car in cars.items():
        (folder / f"{stem}.union.toml").write_text(
            channel_map_text(f"{stem}.dbc", car.latency, UNION_CLOCK)
        )
        (folder / f"{stem}.stamps.toml").write_text(
            channel_map_text(f"{stem}.dbc", car.latency, ('channel = "ax"',))
        )
    lag, _, _ = ay_lag(folder / "late.mf4", folder / "late.latency.toml")
    fixed = folder / "late.fixed.toml"
    fixed.write_text(with_latency((folder / "late.latency.toml").read_text(), "ay", lag))
    cases = [("can.mf4", "can.toml"), ("can.mf4", "can.latency.toml"),
             ("can.blf", "can.latency.toml"), ("can.mf4", "can.stamps.toml"),
             ("rough.mf4", "rough.stamps.toml"), ("rough.mf4", "rough.latency.toml"),
             ("rough.blf", "rough.latency.toml"), ("can.mf4", "can.union.toml"),
             ("still.mf4", "still.union.toml"),
             ("late.mf4", "late.latency.toml"), ("late.mf4", "late.fixed.toml"),
             ("late.blf", "late.fixed.toml")]  # fmt: skip
    for log, channels in cases:
        rmse, note = _rmse(kf, folder / log, folder / channels, truth)
        rows.append(CanScore(log=log, channel_map=channels, rmse=rmse, ratio=rmse / base,
                             note=note))  # fmt: skip
    return rows, lag


def run(args: argparse.Namespace) -> int:
    with tempfile.TemporaryDirectory(prefix="wheelload-can-") as folder:
        rows, lag = can_study(Path(folder), delay=args.delay, seed=args.seed)
    for row in rows:
        shown = f"RMSE {row.rmse:7.2f} N  x{row.ratio:.3f}" if np.isfinite(row.rmse) else row.note
        print(f"{row.log:10s} {row.channel_map:20s} {shown}")
    print(f"ay delayed by {args.delay:g} s: the wiring checks find a lag of {lag:.3f} s "
          f"(error {lag - args.delay:+.3f} s)")  # fmt: skip
    return 0


def register_bench(subparsers) -> None:
    """``wheelload bench can``."""
    parser = subparsers.add_parser(
        "can",
        description=__doc__.splitlines()[0],
    )  # fmt: skip
    parser.add_argument("--delay", type=float, default=0.3, help="ay's hidden delay [s]")
    parser.add_argument("--seed", type=int, default=0, help="seed of the frames' jitter")
    parser.set_defaults(handler=run)
