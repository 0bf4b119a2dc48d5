"""A plant log re-sampled as a CAN car sends it, written as MDF4 bus logging, BLF and ASC.

The car of ``studies/data/can_car.dbc``: the IMU sends specific force
(``IMU_Acc``) and body rates (``IMU_Rate``) at 200 Hz, the damper potentiometers
the four wheel travels (``Dampers``) at 100 Hz, the ABS unit the wheel speeds
(``WheelSpeeds``) at 50 Hz, the chassis unit steering and vehicle speed
(``Chassis``) at 100 Hz, and the wheel-force transducers the reference loads one
corner per frame (``WheelForce``, multiplexed by ``WftCorner``) at 200 Hz, so 50 Hz
per corner. Each frame holds the log's values at its send time, scaled and
rounded as the DBC says; it is logged :attr:`CanCar.latency` after that (5-20 ms,
per frame), plus a random jitter of standard deviation :attr:`CanCar.jitter`.
:attr:`CanCar.signal_delays` delays a signal's content further (a filter inside a
sensor, which nothing in the log declares). With :attr:`CanCar.reorder`, every
:data:`REORDER_EVERY`-th pair of consecutive frames is written in swapped order
(their time stamps kept): out-of-order frames, as a logger with several receive
queues writes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
import pandas as pd

from wheelload.estimators.logs.output_files import atomic_write, write_text
from wheelload.models.conventions import GRAVITY, WHEELS

#: The DBC of the CAN car, shipped with the bundled data.
DBC_NAME = "can_car.dbc"
#: Frame name -> send period [s].
PERIODS = {
    "IMU_Acc": 0.005,
    "IMU_Rate": 0.005,
    "Dampers": 0.010,
    "WheelSpeeds": 0.020,
    "Chassis": 0.010,
    "WheelForce": 0.005,
}
#: Frame name -> its logging latency [s] (5-20 ms, as CAN gateways and loggers add).
LATENCIES = {
    "IMU_Acc": 0.006,
    "IMU_Rate": 0.008,
    "Dampers": 0.012,
    "WheelSpeeds": 0.018,
    "Chassis": 0.010,
    "WheelForce": 0.005,
}
#: Our channel -> (frame, DBC signal, DBC unit): the channel map of the CAN car.
SIGNALS = {
    "ax": ("IMU_Acc", "AccX", "m/s^2"),
    "ay": ("IMU_Acc", "AccY", "m/s^2"),
    "az": ("IMU_Acc", "AccZ", "g"),
    "wx": ("IMU_Rate", "RateX", "deg/s"),
    "wy": ("IMU_Rate", "RateY", "deg/s"),
    "wz": ("IMU_Rate", "RateZ", "deg/s"),
    **{f"d_{w}": ("Dampers", f"Travel{w.upper()}", "mm") for w in WHEELS},
    **{f"ws_{w}": ("WheelSpeeds", f"WheelSpd{w.upper()}", "km/h") for w in WHEELS},
    "steer": ("Chassis", "SteerAngle", "deg"),
    "vx": ("Chassis", "VehSpd", "km/h"),
    **{f"fz_{w}": ("WheelForce", f"Fz{w.upper()}", "N") for w in WHEELS},
}
#: SI value -> DBC unit.
TO_UNIT = {"m/s^2": 1.0, "g": 1.0 / GRAVITY, "deg/s": 180.0 / math.pi, "mm": 1e3,
           "km/h": 3.6, "deg": 180.0 / math.pi, "N": 1.0}  # fmt: skip
REORDER_EVERY = 7
#: The measurement's start (2026-01-01 00:00:00 UTC) in the BLF and ASC headers.
START = 1767225600.0


@dataclass(frozen=True, kw_only=True)
class CanCar:
    """How the CAN car sends a log (module docstring)."""

    latency: dict[str, float] = field(default_factory=lambda: dict(LATENCIES))
    jitter: float = 20e-6  # s, standard deviation of a frame's logging time
    signal_delays: dict[str, float] = field(default_factory=dict)  # our channel -> s
    #: m, front and rear tyre radius: wheel speeds from the log's wheel spins (else vx)
    wheel_radius: tuple[float, float] | None = None
    reorder: bool = False
    seed: int = 0


@dataclass(frozen=True, kw_only=True)
class CanFrames:
    """Frames in file order: logging time [s], identifier, 8 data bytes each."""

    t: np.ndarray
    frame_id: np.ndarray
    data: np.ndarray  # (n, 8) uint8


def dbc_path() -> Path:
    """The bundled DBC of the CAN car."""
    return Path(str(resources.files("wheelload.studies") / "data" / DBC_NAME))


def _signal_values(log: pd.DataFrame, car: CanCar) -> dict[str, np.ndarray]:
    """Our channels the car sends, in SI units, on the log's clock."""
    values = {name: log[name].to_numpy(float) for name in SIGNALS if name in log.columns}
    speed = log["vx"].to_numpy(float)
    for k, wheel in enumerate(WHEELS):
        spin = f"omega_{wheel}"
        radius = None if car.wheel_radius is None else car.wheel_radius[k // 2]
        values[f"ws_{wheel}"] = (
            speed if radius is None or spin not in log else log[spin].to_numpy(float) * radius
        )
    values.setdefault("steer", np.zeros(len(log)))
    return values


def can_frames(log: pd.DataFrame, car: CanCar = CanCar()) -> CanFrames:
    """The frames the CAN car sends while driving ``log`` (a plant log, our columns)."""
    import cantools

    database = cantools.database.load_file(dbc_path())
    rng = np.random.default_rng(car.seed)
    t = log["t"].to_numpy(float)
    values = _signal_values(log, car)
    stamps, ids, payloads = [], [], []
    for frame, period in PERIODS.items():
        message = database.get_message_by_name(frame)
        send = np.arange(t[0], t[-1] + 1e-9, period)
        content = {}
        for name, (owner, signal, unit) in SIGNALS.items():
            if owner == frame:
                sampled = np.interp(send - car.signal_delays.get(name, 0.0), t, values[name])
                content[signal] = sampled * TO_UNIT[unit]
        for k in range(send.size):
            row = {signal: float(series[k]) for signal, series in content.items()}
            if frame == "WheelForce":  # one corner per frame
                corner = k % 4
                row = {"WftCorner": corner, f"Fz{WHEELS[corner].upper()}": row[
                    f"Fz{WHEELS[corner].upper()}"]}  # fmt: skip
            else:
                counter = [s.name for s in message.signals if s.name.endswith("Counter")]
                row.update({name: k % 16 for name in counter})
            payloads.append(np.frombuffer(message.encode(row, strict=False), np.uint8))
        jitter = np.abs(rng.normal(0.0, car.jitter, send.size)) if car.jitter > 0 else 0.0
        stamps.append(send + car.latency[frame] + jitter)
        ids.append(np.full(send.size, message.frame_id))
    stamp = np.concatenate(stamps)
    order = np.argsort(stamp, kind="stable")
    if car.reorder:  # swap the pairs (k, k + 1), k = 0, REORDER_EVERY, ...
        first = np.arange(0, order.size - 1, REORDER_EVERY)
        order[first], order[first + 1] = order[first + 1], order[first].copy()
    return CanFrames(t=stamp[order], frame_id=np.concatenate(ids)[order],
                     data=np.vstack(payloads)[order])  # fmt: skip


def write_bus_logging(frames: CanFrames, path: Path, *, replace: bool = False) -> None:
    """MDF4 bus logging: one channel group of raw ``CAN_DataFrame`` records (ASAM MDF 4.1)."""
    from asammdf import MDF, Signal
    from asammdf.blocks import v4_constants
    from asammdf.blocks.source_utils import Source

    record = np.zeros(frames.t.size, np.dtype([
        ("CAN_DataFrame.BusChannel", "<u1"), ("CAN_DataFrame.ID", "<u4"),
        ("CAN_DataFrame.IDE", "<u1"), ("CAN_DataFrame.DLC", "<u1"),
        ("CAN_DataFrame.DataLength", "<u1"), ("CAN_DataFrame.DataBytes", "(8,)u1"),
    ]))  # fmt: skip
    record["CAN_DataFrame.BusChannel"] = 1
    record["CAN_DataFrame.ID"] = frames.frame_id
    record["CAN_DataFrame.DLC"] = 8
    record["CAN_DataFrame.DataLength"] = 8
    record["CAN_DataFrame.DataBytes"] = frames.data
    source = Source(name="CAN1", path="CAN1", comment="", source_type=v4_constants.SOURCE_BUS,
                    bus_type=v4_constants.BUS_TYPE_CAN)  # fmt: skip
    mdf = MDF(version="4.10")
    try:
        mdf.append([Signal(record, frames.t, name="CAN_DataFrame", source=source)],
                   acq_name="CAN1", acq_source=source)  # fmt: skip
        with atomic_write(path, replace=replace) as temporary:
            mdf.save(temporary, overwrite=True)
    finally:
        mdf.close()


def write_vector_log(frames: CanFrames, path: Path, *, replace: bool = False) -> None:
    """Vector BLF (``.blf``) or ASC (``.asc``), by suffix, through ``python-can``."""
    import can

    with atomic_write(path, replace=replace) as temporary:
        if path.suffix.lower() == ".blf":
            writer = can.BLFWriter(temporary)
            writer.start_timestamp = START
        else:
            writer = can.ASCWriter(temporary)
            writer.log_event("Start of measurement", START)
        try:
            for when, frame_id, data in zip(frames.t, frames.frame_id, frames.data):
                writer.on_message_received(can.Message(
                    timestamp=START + float(when), arbitration_id=int(frame_id),
                    data=bytes(data), is_extended_id=False, channel=0,
                ))  # fmt: skip
        finally:
            writer.stop()


#: The clock of the CAN car's channel maps: the IMU's span at its rate, evenly stepped.
EVEN_CLOCK = ('channel = "ax"', "rate = 200")
#: The clock of the long table of channels on their own stamps.
UNION_CLOCK = ("union = true",)


def channel_map_text(
    dbc: str = DBC_NAME,
    latency: dict[str, float] | None = None,
    clock: tuple[str, ...] = EVEN_CLOCK,
) -> str:
    """The channel map of the CAN car (TOML); ``latency``: frame -> its ``latency`` key;
    ``clock``: the lines of its ``[clock]`` table."""
    lines = ["# The CAN car's signals (studies/data/can_car.dbc) as our channels.",
             f'dbc = "{dbc}"', "", "[clock]", *clock, ""]  # fmt: skip
    for name, (frame, signal, unit) in SIGNALS.items():
        lines += [f"[channels.{name}]", f'source = "{signal}"', f'unit = "{unit}"']
        if latency and frame in latency:
            lines.append(f"latency = {latency[frame]:.6g}")
        lines.append("")
    return "\n".join(lines)


def can_outputs(folder: Path, stem: str) -> list[Path]:
    """The files :func:`write_can_logs` writes."""
    names = [f"{stem}.mf4", f"{stem}.blf", f"{stem}.dbc", f"{stem}.toml", f"{stem}.latency.toml"]
    return [folder / name for name in names]


def write_can_logs(
    log: pd.DataFrame, folder: Path, stem: str, car: CanCar = CanCar(), *, replace: bool = False
) -> list[Path]:
    """``STEM.mf4``, ``STEM.blf``, the DBC (``STEM.dbc``) and two channel maps in ``folder``:
    ``STEM.toml`` without latency keys, ``STEM.latency.toml`` with the car's frame latencies."""
    frames = can_frames(log, car)
    paths = can_outputs(folder, stem)
    write_bus_logging(frames, paths[0], replace=replace)
    write_vector_log(frames, paths[1], replace=replace)
    write_text(paths[2], dbc_path().read_text(), replace=replace)
    dbc = paths[2].name
    write_text(paths[3], channel_map_text(dbc), replace=replace)
    write_text(paths[4], channel_map_text(dbc, latency=car.latency), replace=replace)
    return paths
