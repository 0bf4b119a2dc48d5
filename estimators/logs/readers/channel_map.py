"""Channel maps: a log's own channel names, units and signs onto the log format.

A TOML file (``wheelload channels --template`` prints a commented one)::

    [clock]
    channel = "ax"       # output clock: the time stamps of this channel
    method = "linear"    # default resampling: "linear" or "hold"
    max_gap = 0.1        # s, a longer gap between source samples is missing

    [channels.vx]
    source = "VehSpd"    # the channel's name in the log
    unit = "km/h"        # converted by the units table (units.py)
    sign = 1             # -1 for an axis that points the other way
    method = "hold"      # this channel only (a CAN signal)
    latency = 0.012      # s, this channel's time stamps are shifted back by it

    [channels.d_fl]
    source = "DamperPot_FL"
    unit = "mm"
    motion_ratio = 0.7   # damper travel / wheel travel: d = d_damper / ratio

Our channel names (targets) are those of the log format (signals.py) plus
``ws_fl ws_fr ws_rl ws_rr``, wheel speeds [m/s] from which ``vx`` is taken
when it is not mapped; a wheel speed in ``rpm`` needs ``radius`` [m] and
``ratio`` (shaft turns per wheel turn, default 1). For CSV and Parquet logs
``[time]`` names the time column and its unit; MDF4 and ERG channels carry
their own time stamps. A CAN log (MDF4 bus logging, Vector BLF or ASC) is decoded with
the DBC file named by the top-level key ``dbc = "car.dbc"`` (relative to the map), and
``source`` is a signal name of that DBC (``readers/can_bus.py``). ``[clock] union = true``
puts every channel on the union of the channels' time stamps, each with NaN where it has
no new value, instead of resampling onto one clock channel; ``[clock] rate = 200``
resamples onto a uniform clock at that rate over the clock channel's span (time stamps
that jitter, as a CAN logger's do, onto the even steps the filter's differentiators
need). Every key is checked: an unknown key, target or unit, or a unit of the wrong kind,
is an error naming the file and the key.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators.logs.readers.resample import Method, resample
from wheelload.estimators.logs.readers.union import on_union, union_clock
from wheelload.estimators.logs.readers.units import UNITS, Kind, UnitError, unit_factor
from wheelload.models.conventions import WHEELS
from wheelload.models.runtime.toml_file import TomlFileKind, read_toml

if TYPE_CHECKING:
    import pandas as pd

#: our channel name -> kind of quantity
TARGETS: dict[str, Kind] = {
    "vx": Kind.SPEED,
    "ax": Kind.ACCELERATION,
    "ay": Kind.ACCELERATION,
    "az": Kind.ACCELERATION,
    "wx": Kind.ANGULAR_RATE,
    "wy": Kind.ANGULAR_RATE,
    "wz": Kind.ANGULAR_RATE,
    **{f"d_{w}": Kind.LENGTH for w in WHEELS},
    **{f"v_{w}": Kind.SPEED for w in WHEELS},
    **{f"fz_{w}": Kind.FORCE for w in WHEELS},
    **{f"ws_{w}": Kind.SPEED for w in WHEELS},
    **{f"az_{w}": Kind.ACCELERATION for w in WHEELS},  # hub accelerometers (body z)
    **{f"omega_{w}": Kind.ANGULAR_RATE for w in WHEELS},  # wheel spins
    **{f"torque_{w}": Kind.TORQUE for w in WHEELS},  # drive minus brake torque at the wheel
    "steer": Kind.ANGLE,  # front road-wheel angle, > 0 to the left
    **{f"fx_{w}": Kind.FORCE for w in WHEELS},  # reference tyre forces, tyre frame
    **{f"fy_{w}": Kind.FORCE for w in WHEELS},
}
#: groups filled with missing (NaN) columns when only some of them are mapped
GROUPS = (
    tuple(f"d_{w}" for w in WHEELS),
    tuple(f"v_{w}" for w in WHEELS),
    tuple(f"fz_{w}" for w in WHEELS),
    tuple(f"az_{w}" for w in WHEELS),
)
DEFAULT_MAX_GAP = 0.1  # s
_log = logging.getLogger("wheelload")


class ChannelMapError(ValueError):
    """A channel map that cannot be used: names the file and the key."""


CHANNEL_MAP_FILE = TomlFileKind(
    error=ChannelMapError,
    missing="no such channel map",
    folder="is a folder, not a channel map: give the map's .toml file",
    not_utf8="the channel map is not UTF-8 text (byte {byte}): save it as UTF-8",
    not_toml="the channel map is not valid TOML: {error}",
    unreadable="the channel map cannot be read: {error}",
)


@dataclass(frozen=True, kw_only=True)
class Channel:
    """One source channel: time stamps [s], values (source units), declared unit."""

    t: np.ndarray
    values: np.ndarray
    unit: str = ""


@dataclass(frozen=True, kw_only=True)
class ChannelSpec:
    """How one of our channels is made from a source channel; ``unit`` "" takes the unit
    the log declares (MDF4, the units row of an AiM or MoTeC export)."""

    source: str
    unit: str = ""
    sign: float = 1.0
    motion_ratio: float = 1.0
    radius: float | None = None
    ratio: float = 1.0
    method: Method | None = None
    latency: float = 0.0  # s, the source's time stamps minus this are the measurement's


@dataclass(frozen=True, kw_only=True)
class Clock:
    """The output clock: the time stamps of ``channel``, or with ``union`` those of every
    channel (each NaN where it has no sample); default method and gap."""

    channel: str = "ax"
    method: Method = Method.LINEAR
    max_gap: float = DEFAULT_MAX_GAP
    union: bool = False
    rate: float | None = None  # Hz: a uniform clock over the clock channel's span


@dataclass(frozen=True, kw_only=True)
class TimeColumn:
    """The time column of a CSV or Parquet log."""

    source: str
    unit: str = "s"


@dataclass(frozen=True, kw_only=True)
class ChannelMap:
    """A validated channel map (see module docstring)."""

    channels: dict[str, ChannelSpec]
    clock: Clock = Clock()
    time: TimeColumn | None = None
    source: str = "<channel map>"
    dbc: Path | None = None  # the DBC file that decodes a CAN log

    def sources(self) -> list[str]:
        """The source channel names the map reads."""
        names = [spec.source for spec in self.channels.values()]
        return names + ([self.time.source] if self.time else [])


def identity_map(names: list[str], source: str) -> ChannelMap:
    """A map that takes the log's channels named as ours, in SI units."""
    channels = {
        name: ChannelSpec(source=name, unit=TARGETS[name].value)
        for name in names
        if name in TARGETS
    }
    if "ax" not in channels:
        raise ChannelMapError(f"{source}: no channel named 'ax' (give a channel map, --channels)")
    return ChannelMap(channels=channels, source=f"{source} (channels named as the log format)")


def _table(value: object, key: str, where: str) -> dict:
    if not isinstance(value, dict):
        raise ChannelMapError(f"{where}: key '{key}' must be a table [{key}]")
    return value


def _keys(table: dict, allowed: set[str], required: set[str], prefix: str, where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ChannelMapError(f"{where}: unknown key '{prefix}{unknown[0]}'")
    missing = sorted(required - set(table))
    if missing:
        raise ChannelMapError(f"{where}: missing key '{prefix}{missing[0]}'")


def _number(table: dict, key: str, prefix: str, where: str, positive: bool = True) -> float:
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ChannelMapError(f"{where}: key '{prefix}{key}' must be a number, got {value!r}")
    if positive and not value > 0:
        raise ChannelMapError(f"{where}: key '{prefix}{key}' must be > 0, got {value!r}")
    return float(value)


def _method(value: object, key: str, where: str) -> Method:
    names = [m.value for m in Method]
    if value not in names:
        raise ChannelMapError(f"{where}: key '{key}' must be one of {', '.join(names)}")
    return Method(value)


def _string(table: dict, key: str, prefix: str, where: str) -> str:
    value = table[key]
    if not isinstance(value, str) or not value.strip():
        raise ChannelMapError(f"{where}: key '{prefix}{key}' must be a non-empty string")
    return value


def _channel(name: str, table: dict, where: str) -> ChannelSpec:
    prefix = f"channels.{name}."
    _keys(table, {"source", "unit", "sign", "motion_ratio", "radius", "ratio", "method",
                  "latency"}, {"source"}, prefix, where)  # fmt: skip
    unit = _string(table, "unit", prefix, where) if "unit" in table else ""
    if unit:
        try:
            unit_factor(unit, TARGETS[name], f"{where}: key '{prefix}unit'")
        except UnitError as error:
            raise ChannelMapError(str(error)) from None
    sign = 1.0
    if "sign" in table:
        sign = _number(table, "sign", prefix, where, positive=False)
        if sign not in (1.0, -1.0):
            raise ChannelMapError(f"{where}: key '{prefix}sign' must be 1 or -1, got {sign:g}")
    motion_ratio = 1.0
    if "motion_ratio" in table:
        if not name.startswith(("d_", "v_")):
            raise ChannelMapError(
                f"{where}: key '{prefix}motion_ratio' applies to travel channels d_*, v_* only"
            )
        motion_ratio = _number(table, "motion_ratio", prefix, where)
    rotation = unit.strip() in ("rpm", "1/min", "rad/s_wheel")
    wheel_speed = name.startswith("ws_")
    if ("radius" in table or "ratio" in table or rotation) and not (
        wheel_speed or (rotation and name.startswith("omega_") and "radius" not in table)
    ):
        raise ChannelMapError(
            f"{where}: channel '{name}': a rotation speed is for wheel speeds ws_* and wheel "
            "spins omega_* only, keys radius, ratio for ws_* only"
        )
    if rotation and wheel_speed and "radius" not in table:
        raise ChannelMapError(
            f"{where}: missing key '{prefix}radius' (rolling radius [m]) for unit '{unit}'"
        )
    return ChannelSpec(
        source=_string(table, "source", prefix, where),
        unit=unit,
        sign=sign,
        motion_ratio=motion_ratio,
        radius=_number(table, "radius", prefix, where) if "radius" in table else None,
        ratio=_number(table, "ratio", prefix, where) if "ratio" in table else 1.0,
        method=_method(table["method"], f"{prefix}method", where) if "method" in table else None,
        latency=_latency(table, prefix, where),
    )


MAX_LATENCY = 10.0  # s, a larger channel latency is a unit mistake (ms for s)


def _latency(table: dict, prefix: str, where: str) -> float:
    """The ``latency`` key [s], 0 <= latency < :data:`MAX_LATENCY`; 0 without it."""
    if "latency" not in table:
        return 0.0
    latency = _number(table, "latency", prefix, where, positive=False)
    if not 0.0 <= latency < MAX_LATENCY:
        raise ChannelMapError(
            f"{where}: key '{prefix}latency' must be in [0, {MAX_LATENCY:g}) s, got {latency:g} "
            "(seconds, not milliseconds)"
        )
    return latency


def _dbc(table: dict, where: str) -> Path | None:
    """The top-level ``dbc`` key: the DBC file, relative to the map's folder."""
    if "dbc" not in table:
        return None
    path = Path(_string(table, "dbc", "", where)).expanduser()
    if not path.is_absolute() and Path(where).parent.is_dir():
        path = Path(where).parent / path
    return path


def channel_map_from_dict(table: dict, where: str = "<channel map>") -> ChannelMap:
    """Validate a parsed channel-map table."""
    _keys(table, {"clock", "time", "channels", "dbc"}, {"channels"}, "", where)
    clock = Clock()
    if "clock" in table:
        raw = _table(table["clock"], "clock", where)
        _keys(raw, {"channel", "method", "max_gap", "union", "rate"}, set(), "clock.", where)
        if not isinstance(raw.get("union", False), bool):
            raise ChannelMapError(f"{where}: key 'clock.union' must be true or false")
        default = Clock()
        clock = Clock(
            channel=_string(raw, "channel", "clock.", where)
            if "channel" in raw
            else default.channel,
            method=_method(raw["method"], "clock.method", where)
            if "method" in raw
            else default.method,
            max_gap=_number(raw, "max_gap", "clock.", where)
            if "max_gap" in raw
            else default.max_gap,
            union=raw.get("union", False),
            rate=_number(raw, "rate", "clock.", where) if "rate" in raw else None,
        )
        if clock.union and clock.rate is not None:
            raise ChannelMapError(
                f"{where}: keys 'clock.union' and 'clock.rate' exclude each other"
            )
    time = None
    if "time" in table:
        raw = _table(table["time"], "time", where)
        _keys(raw, {"source", "unit"}, {"source"}, "time.", where)
        unit = _string(raw, "unit", "time.", where) if "unit" in raw else "s"
        try:
            unit_factor(unit, Kind.TIME, f"{where}: key 'time.unit'")
        except UnitError as error:
            raise ChannelMapError(str(error)) from None
        time = TimeColumn(source=_string(raw, "source", "time.", where), unit=unit)
    raw_channels = _table(table["channels"], "channels", where)
    unknown = sorted(set(raw_channels) - set(TARGETS))
    if unknown:
        raise ChannelMapError(
            f"{where}: unknown channel 'channels.{unknown[0]}'; ours are {', '.join(TARGETS)}"
        )
    channels = {
        name: _channel(name, _table(value, f"channels.{name}", where), where)
        for name, value in raw_channels.items()
    }
    if clock.channel not in channels:
        raise ChannelMapError(
            f"{where}: key 'clock.channel' is '{clock.channel}', which the map does not define"
        )
    return ChannelMap(
        channels=channels, clock=clock, time=time, source=where, dbc=_dbc(table, where)
    )


def load_channel_map(path: str | Path) -> ChannelMap:
    """Read and validate a channel-map TOML file."""
    path = Path(path)
    table = read_toml(path, CHANNEL_MAP_FILE)
    return channel_map_from_dict(table, str(path))


def convert(spec: ChannelSpec, kind: Kind, values: np.ndarray, where: str) -> np.ndarray:
    """Source values to SI, with sign, motion ratio and wheel radius applied."""
    factor = unit_factor(spec.unit, kind, where)
    if spec.radius is not None and spec.unit.strip() in ("rpm", "1/min", "rad/s_wheel"):
        factor = factor * spec.radius / spec.ratio
    return spec.sign * factor * np.asarray(values, float) / spec.motion_ratio


def check_stamps(t: np.ndarray, source: str, name: str, where: str) -> None:
    """The time stamps of a source channel go forward: else an error naming it and the row.

    Resampling (:func:`~wheelload.estimators.logs.readers.resample.resample`) needs them
    sorted; a stamp that goes back (a logger clock reset, two recordings joined)
    would be interpolated silently out of order.
    """
    t = np.asarray(t, float)
    rows = np.flatnonzero(np.isfinite(t))
    back = np.flatnonzero(np.diff(t[rows]) < 0.0)
    if back.size:
        before, row = rows[back[0]], rows[back[0] + 1]
        raise ChannelMapError(
            f"{where}: channel '{source}' (for '{name}') has time stamps that go back at "
            f"sample {row} (t = {t[before]:.6g} s then {t[row]:.6g} s): export the log with "
            "one increasing clock per channel (a logger restart splits it into two logs)"
        )


#: A channel logged slower than ``clock.max_gap`` (a 1 Hz speed on CAN) is resampled over
#: gaps up to this many of its own median intervals, not dropped between its samples.
SLOW_GAP_RATIO = 1.5


def slow_gap(t: np.ndarray, max_gap: float) -> float:
    """The longest gap [s] to bridge for a channel with time stamps ``t``: ``max_gap``, or
    :data:`SLOW_GAP_RATIO` times the channel's median interval if that is longer."""
    t = np.asarray(t, float)
    t = t[np.isfinite(t)]
    if t.size < 2:
        return max_gap
    return max(max_gap, SLOW_GAP_RATIO * float(np.median(np.diff(t))))


def _check_rotation(name: str, spec: ChannelSpec, where: str) -> None:
    """A rotation speed the log declares is a wheel speed's (with its radius) or a wheel
    spin's: else an error naming the key (the map's own units are checked when read)."""
    if spec.unit not in ("rpm", "1/min", "rad/s_wheel"):
        return
    if name.startswith("ws_") and spec.radius is None:
        raise ChannelMapError(
            f"{where}: the log gives '{spec.unit}': key 'channels.{name}.radius' (rolling "
            "radius [m]) is needed"
        )
    if not name.startswith(("ws_", "omega_")):
        raise ChannelMapError(
            f"{where}: the log gives '{spec.unit}', a rotation speed, for '{name}': give key "
            f"'channels.{name}.unit'"
        )


def apply_channel_map(raw: dict[str, Channel], channel_map: ChannelMap, where: str) -> pd.DataFrame:
    """Our columns on one clock, in SI units (a frame for ``signals_from_frame``)."""
    import pandas as pd

    for name, spec in channel_map.channels.items():
        if spec.source not in raw:
            raise ChannelMapError(
                f"{where}: channel '{spec.source}' (for '{name}' in {channel_map.source}) "
                "is not in the log"
            )
        declared = raw[spec.source].unit.strip()
        given = spec.unit.strip()
        if not given and not declared:
            raise ChannelMapError(
                f"{where}: channel '{spec.source}' declares no unit in the log: give key "
                f"'channels.{name}.unit' in {channel_map.source}"
            )
        same = declared == given or (declared in UNITS and UNITS.get(declared) == UNITS.get(given))
        if declared and given and not same:
            raise ChannelMapError(
                f"{where}: channel '{spec.source}' is declared in '{declared}' in the log but "
                f"in '{spec.unit}' in {channel_map.source} (key 'channels.{name}.unit')"
            )
    for name, spec in channel_map.channels.items():
        check_stamps(raw[spec.source].t, spec.source, name, where)
    stamps = {
        name: np.asarray(raw[spec.source].t, float) - spec.latency
        for name, spec in channel_map.channels.items()
    }
    if channel_map.clock.union:
        clock = union_clock(list(stamps.values()))
    else:
        clock = stamps[channel_map.clock.channel]
    rate = channel_map.clock.rate
    if rate is not None and clock.size:
        clock = clock[0] + np.arange(int((clock[-1] - clock[0]) * rate) + 1) / rate
    columns: dict[str, np.ndarray] = {"t": clock}
    for name, spec in channel_map.channels.items():
        channel = raw[spec.source]
        if not spec.unit.strip():  # the log's own unit
            spec = dataclasses.replace(spec, unit=channel.unit.strip())
            _check_rotation(name, spec, f"{where}: channel '{spec.source}' (for '{name}')")
        try:
            values = convert(
                spec, TARGETS[name], channel.values, f"{where}: channel '{spec.source}'"
            )
        except UnitError as error:
            raise ChannelMapError(
                f"{error} (key 'channels.{name}.unit' in {channel_map.source})"
            ) from None
        if channel_map.clock.union:
            columns[name] = on_union(stamps[name], values, clock)
            continue
        method = spec.method or channel_map.clock.method
        max_gap = slow_gap(stamps[name], channel_map.clock.max_gap)
        if max_gap > channel_map.clock.max_gap:
            _log.warning(
                "%s: note: channel '%s' (for '%s') is logged every %.3g s, slower than "
                "clock.max_gap = %g s: %s onto the clock over gaps up to %.3g s",
                where, spec.source, name, max_gap / SLOW_GAP_RATIO, channel_map.clock.max_gap,
                "held" if method is Method.HOLD else "interpolated linearly", max_gap,
            )  # fmt: skip
        columns[name] = resample(stamps[name], values, clock, method, max_gap)
    for group in GROUPS:
        if any(name in columns for name in group):
            for name in group:
                columns.setdefault(name, np.full(clock.shape, np.nan))
    return pd.DataFrame(columns)


def channel_map_template() -> str:
    """A commented channel map to edit (a Formula Student style logger)."""
    return TEMPLATE


TEMPLATE = """\
# wheelload channel map: your log's channels -> the log format (SI, ISO 8855).
# Use with: wheelload estimate LOG --vehicle car.toml --channels this.toml
# Every key is checked; unknown keys, channels and units are errors.
# A CAN log (.mf4 bus logging, .blf, .asc): dbc = "car.dbc" (the DBC that decodes it,
# relative to this map) at the top, and each source is a signal name of that DBC.
# Units: s ms us | m cm mm in | m/s mm/s km/h mph | m/s^2 g | rad/s deg/s | N kN
#        | N m kNm | rad deg | rpm (wheel speeds with radius and ratio; wheel spins
#        omega_*). "g" is standard gravity.

[clock]
channel = "ax"       # output clock: this channel's time stamps (the IMU's)
# rate = 200         # Hz: a uniform clock over that channel's span (jittering CAN stamps)
# union = true       # or each channel at its own stamps (NaN between; not with rate)
method = "linear"    # default resampling: "linear" interpolation or zero-order "hold"
max_gap = 0.1        # s; a longer gap between source samples is a missing sample

# CSV / Parquet logs only: the time column (MDF4, ERG and AiM / MoTeC CSV exports
# carry their own; their declared units stand for a missing 'unit' key).
# [time]
# source = "Time"
# unit = "s"

[channels.ax]
source = "IMU_AccX"
unit = "m/s^2"
[channels.ay]
source = "IMU_AccY"
unit = "m/s^2"
sign = -1            # this IMU's y axis points right; ours points left
[channels.az]        # leave az out to assume g (flagged)
source = "IMU_AccZ"
unit = "g"
[channels.wx]        # body rates are optional
source = "IMU_GyrX"
unit = "deg/s"
[channels.wy]
source = "IMU_GyrY"
unit = "deg/s"
[channels.wz]
source = "IMU_GyrZ"
unit = "deg/s"

[channels.vx]        # leave vx out to take it from the wheel speeds, or to run without aero
source = "VehSpd_CAN"
unit = "km/h"
method = "hold"      # a CAN signal: zero-order hold
# latency = 0.012    # s, logged this late: its time stamps are shifted back by it

# Suspension travel, compression positive. motion_ratio = damper travel /
# wheel travel. Leave a corner out for a dead sensor, all four for IMU-only.
[channels.d_fl]
source = "DamperPot_FL"
unit = "mm"
motion_ratio = 0.7
[channels.d_fr]
source = "DamperPot_FR"
unit = "mm"
motion_ratio = 0.7
[channels.d_rl]
source = "DamperPot_RL"
unit = "mm"
motion_ratio = 0.75
[channels.d_rr]
source = "DamperPot_RR"
unit = "mm"
motion_ratio = 0.75

# Wheel speeds (used for vx when vx is not mapped).
# [channels.ws_rl]
# source = "WheelSpd_RL"
# unit = "rpm"
# radius = 0.26      # m, rolling radius
# ratio = 1.0        # sensor shaft turns per wheel turn

# Wheel channels of the tyre-force methods (estimate --method tyre-forces), per wheel.
# [channels.omega_fl]
# source = "WheelSpd_FL"
# unit = "rpm"       # the wheel's spin: rpm or rad/s (no radius)
# [channels.torque_fl]
# source = "WheelTrq_FL"   # drive minus brake torque at the wheel
# unit = "N m"
# [channels.steer]
# source = "SteerAngle"    # front road-wheel angle, > 0 to the left
# unit = "deg"
"""
