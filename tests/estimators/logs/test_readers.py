"""Log readers: a real asammdf MDF4 file and a CarMaker ERG through channel maps."""

import math

import numpy as np
import pandas as pd
import pytest
from asammdf import MDF, Signal

from wheelload.estimators import LogError, read_log
from wheelload.estimators.logs.readers import Method, channel_map_template
from wheelload.estimators.logs.readers.erg import write_erg
from wheelload.estimators.logs.readers.resample import resample
from wheelload.models import GRAVITY
from wheelload.models.conventions import WHEELS

RATIO = {"fl": 0.7, "fr": 0.7, "rl": 0.75, "rr": 0.75}  # damper / wheel travel
DURATION = 2.0
IMU_RATE, TRAVEL_RATE, CAN_RATE = 1000, 100, 50

MAP = """
[clock]
channel = "ax"
method = "linear"
max_gap = 0.1

[channels.ax]
source = "IMU_AccX"
unit = "m/s^2"
[channels.ay]
source = "IMU_AccY"
unit = "m/s^2"
sign = -1
[channels.az]
source = "IMU_AccZ"
unit = "g"
[channels.wx]
source = "IMU_GyrX"
unit = "deg/s"
[channels.wy]
source = "IMU_GyrY"
unit = "deg/s"
[channels.wz]
source = "IMU_GyrZ"
unit = "deg/s"
[channels.vx]
source = "VehSpd_CAN"
unit = "km/h"
method = "hold"
""" + "".join(
    f'[channels.d_{w}]\nsource = "Damper_{w.upper()}"\nunit = "mm"\nmotion_ratio = {RATIO[w]}\n'
    for w in WHEELS
)


def _source_channels():
    """Raw channels at 1 kHz (IMU), 100 Hz (dampers, mm) and 50 Hz (CAN speed, km/h)."""
    t_imu = np.arange(int(DURATION * IMU_RATE) + 1) / IMU_RATE
    t_travel = np.arange(int(DURATION * TRAVEL_RATE) + 1) / TRAVEL_RATE
    t_can = np.arange(int(DURATION * CAN_RATE) + 1) / CAN_RATE
    imu = {
        "IMU_AccX": 1.5 * np.sin(2.0 * t_imu),
        "IMU_AccY": -4.0 * np.sin(3.0 * t_imu),  # points right: the map flips it
        "IMU_AccZ": 1.0 + 0.02 * np.cos(5.0 * t_imu),  # g
        "IMU_GyrX": 3.0 * np.sin(t_imu),  # deg/s
        "IMU_GyrY": 2.0 * np.cos(t_imu),
        "IMU_GyrZ": 10.0 * np.sin(0.5 * t_imu),
    }
    travel = {
        f"Damper_{w.upper()}": 8.0 * np.sin(2.0 * np.pi * 1.3 * t_travel + i)
        for i, w in enumerate(WHEELS)
    }
    can = {"VehSpd_CAN": 80.0 + 5.0 * np.sin(t_can)}
    return (t_imu, imu), (t_travel, travel), (t_can, can)


def _si_frame():
    """The same log in SI on the 1 kHz clock, resampled by hand (independent of the reader)."""
    (t, imu), (_, travel), (_, can) = _source_channels()
    i = np.arange(t.size)
    frame = {
        "t": t,
        "ax": imu["IMU_AccX"],
        "ay": -imu["IMU_AccY"],
        "az": imu["IMU_AccZ"] * GRAVITY,
        "wx": imu["IMU_GyrX"] * math.pi / 180,
        "wy": imu["IMU_GyrY"] * math.pi / 180,
        "wz": imu["IMU_GyrZ"] * math.pi / 180,
        "vx": can["VehSpd_CAN"][i // (IMU_RATE // CAN_RATE)] / 3.6,  # zero-order hold
    }
    step = IMU_RATE // TRAVEL_RATE
    j = np.minimum(i // step, len(travel["Damper_FL"]) - 2)
    frac = (i - j * step) / step
    for w in WHEELS:
        y = travel[f"Damper_{w.upper()}"]
        frame[f"d_{w}"] = (y[j] + frac * (y[j + 1] - y[j])) * 1e-3 / RATIO[w]
    return pd.DataFrame(frame)


def _write_mdf(path):
    groups = _source_channels()
    units = {"IMU_AccX": "m/s^2", "IMU_AccY": "m/s^2", "IMU_AccZ": "g", "VehSpd_CAN": "km/h"}
    with MDF(version="4.10") as mdf:
        for t, channels in groups:
            signals = [
                Signal(samples=values, timestamps=t, name=name, unit=units.get(name, ""))
                for name, values in channels.items()
            ]
            mdf.append(signals)
        mdf.save(path, overwrite=True)
    return path


@pytest.fixture
def channel_map(tmp_path):
    path = tmp_path / "map.toml"
    path.write_text(MAP)
    return path


def _assert_same_signals(a, b):
    # 1e-9: both are float64 computations of the same values (CSV written with 17 digits).
    for name in ("t", "vx", "acc", "d", "v", "rates"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-9)


def test_mdf4_through_a_channel_map_equals_the_si_csv(tmp_path, channel_map):
    mdf = _write_mdf(tmp_path / "drive.mf4")
    csv = tmp_path / "drive.csv"
    _si_frame().to_csv(csv, index=False, float_format="%.17g")
    from_mdf = read_log(mdf, channels=channel_map)
    from_csv = read_log(csv)
    assert len(from_mdf) == IMU_RATE * DURATION + 1
    _assert_same_signals(from_mdf, from_csv)
    assert from_mdf.velocities_derived and np.isfinite(from_mdf.v[10:]).all()


def test_erg_through_a_channel_map_equals_the_si_csv(tmp_path, channel_map):
    # One ERG clock: resample the slower channels to 1 kHz with the source values held.
    (t, imu), (t_travel, travel), (t_can, can) = _source_channels()
    columns = {"Time": t, **imu}
    for name, values in travel.items():
        columns[name] = np.interp(t, t_travel, values)
    columns["VehSpd_CAN"] = can["VehSpd_CAN"][np.arange(t.size) // (IMU_RATE // CAN_RATE)]
    path = tmp_path / "run.erg"
    write_erg(path, columns, {"Time": "s", "IMU_AccZ": "g", "VehSpd_CAN": "km/h"})
    csv = tmp_path / "drive.csv"
    _si_frame().to_csv(csv, index=False, float_format="%.17g")
    _assert_same_signals(read_log(path, channels=channel_map), read_log(csv))


def test_a_can_dropout_longer_than_the_gap_is_missing_not_held():
    t = np.arange(0.0, 1.0, 0.02)
    values = np.arange(t.size, dtype=float)
    keep = (t < 0.29) | (t > 0.61)  # frames 15-30 lost: 0.34 s from 0.28 to 0.62
    clock = np.arange(0.0, 0.98, 0.001)
    held = resample(t[keep], values[keep], clock, Method.HOLD, max_gap=0.1)
    assert held[clock.searchsorted(0.285)] == values[14]  # last frame before the gap, held
    assert np.isnan(held[(clock > 0.381) & (clock < 0.619)]).all()  # older than 0.1 s
    assert held[clock.searchsorted(0.63)] == values[31]
    linear = resample(t[keep], values[keep], clock, Method.LINEAR, max_gap=0.1)
    assert np.isnan(linear[(clock > 0.281) & (clock < 0.619)]).all()
    assert linear[clock.searchsorted(0.281) - 1] == values[14]
    np.testing.assert_allclose(linear[clock.searchsorted(0.65)], 0.65 / 0.02, rtol=1e-9)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (('unit = "mm"', 'unit = "furlong"', 1), r"unknown unit 'furlong'"),
        (('unit = "km/h"', 'unit = "mm"', 1), r"unit 'mm' is a length, the channel needs a speed"),
        (("sign = -1", "sign = 2", 1), r"key 'channels.ay.sign' must be 1 or -1"),
        (("[channels.vx]", "[channels.speed]", 1), r"unknown channel 'channels.speed'"),
        (('source = "IMU_GyrZ"', 'source = "Gyro_Z"', 1), r"drive.mf4: no channel 'Gyro_Z'"),
        (
            ('source = "IMU_GyrZ"', "source = 5", 1),
            r"key 'channels.wz.source' must be a non-empty string",
        ),
        (
            ('source = "IMU_GyrZ"', 'source = "  "', 1),
            r"key 'channels.wz.source' must be a non-empty string",
        ),
    ],
)
def test_channel_map_errors_name_the_key(tmp_path, channel_map, edit, message):
    mdf = _write_mdf(tmp_path / "drive.mf4")
    channel_map.write_text(MAP.replace(*edit))
    with pytest.raises(LogError, match=message):
        read_log(mdf, channels=channel_map)


def test_declared_unit_must_agree_with_the_map(tmp_path, channel_map):
    mdf = _write_mdf(tmp_path / "drive.mf4")
    channel_map.write_text(MAP.replace('unit = "g"', 'unit = "m/s^2"'))
    with pytest.raises(LogError, match=r"'IMU_AccZ' is declared in 'g' in the log"):
        read_log(mdf, channels=channel_map)


def test_template_is_a_valid_map(tmp_path):
    from wheelload.estimators.logs.readers import load_channel_map

    path = tmp_path / "template.toml"
    path.write_text(channel_map_template())
    channel_map = load_channel_map(path)
    assert channel_map.channels["ay"].sign == -1.0
    assert channel_map.channels["vx"].method is Method.HOLD
    assert channel_map.channels["d_rl"].motion_ratio == 0.75


def test_estimate_and_channels_commands_read_through_the_map(tmp_path, channel_map, capsys):
    from wheelload.models import example_vehicle_path
    from wheelload.studies.cli import main

    mdf = _write_mdf(tmp_path / "drive.mf4")
    assert main(["channels", "--list", str(mdf)]) == 0
    assert "Damper_FL" in capsys.readouterr().out
    assert main(["channels", str(channel_map), "--log", str(mdf)]) == 0
    assert "2001 samples at 1000.0 Hz; four travel sensors" in capsys.readouterr().out
    out = tmp_path / "est.csv"
    vehicle = str(example_vehicle_path())
    argv = ["estimate", str(mdf), "--vehicle", vehicle, "--channels", str(channel_map)]
    assert main([*argv, "--out", str(out)]) == 0
    assert np.isfinite(pd.read_csv(out)["fz_rr"]).all()
    assert main(["estimate", str(mdf), "--vehicle", vehicle]) == 2  # no map: names not ours
    assert "no channel named 'ax' (give a channel map, --channels)" in capsys.readouterr().err


def test_erg_with_mixed_types_padding_and_big_endian(tmp_path):
    from wheelload.estimators.logs.readers.erg import HEADER, read_erg_channels

    dtype = np.dtype([("Time", ">f8"), ("Car.ax", ">f4"), ("pad", "V4"), ("Count", ">i2")])
    records = np.zeros(3, dtype=dtype)
    records["Time"] = [0.0, 0.01, 0.02]
    records["Car.ax"] = [0.5, -1.25, 2.0]  # exact in float32
    records["Count"] = [1, -2, 3]
    path = tmp_path / "run.erg"
    path.write_bytes(HEADER + records.tobytes())
    (tmp_path / "run.erg.info").write_text(
        "#INFOFILE1.1\nFile.Format = erg\nFile.ByteOrder = BigEndian\n"
        "File.At.1.Name = Time\nFile.At.1.Type = Double\n"
        "File.At.2.Name = Car.ax\nFile.At.2.Type = Float\n"
        "File.At.3.Name = pad\nFile.At.3.Type = 4 Bytes\n"
        "File.At.4.Name = Count\nFile.At.4.Type = Short\n"
        "Quantity.Car.ax.Unit = m/s^2\n"
    )
    channels = read_erg_channels(path, ["Car.ax", "Count"])
    np.testing.assert_array_equal(channels["Car.ax"].values, [0.5, -1.25, 2.0])
    np.testing.assert_array_equal(channels["Count"].values, [1, -2, 3])
    np.testing.assert_array_equal(channels["Count"].t, [0.0, 0.01, 0.02])
    assert channels["Car.ax"].unit == "m/s^2" and channels["Count"].unit == ""
    path.write_bytes(HEADER + records.tobytes()[:-3])  # truncated
    with pytest.raises(ValueError, match="51 data bytes is not a whole number of 18-byte records"):
        read_erg_channels(path, ["Car.ax"])


def test_csv_with_its_own_names_and_units_through_a_map(tmp_path):
    # A Formula Student style CSV: time in ms, acceleration in g with y pointing right,
    # damper potentiometers in mm (motion ratio 0.8), no az, no vx, no body rates.
    from wheelload.studies.pipeline.example_log import example_log_path

    si = pd.read_csv(example_log_path())
    raw = pd.DataFrame({
        "Time_ms": si["t"] * 1000.0,
        "AccX_g": si["ax"] / GRAVITY,
        "AccY_g": -si["ay"] / GRAVITY,
        **{f"Pot_{w.upper()}": si[f"d_{w}"] * 1000.0 * 0.8 for w in WHEELS},
    })  # fmt: skip
    log = tmp_path / "fs.csv"
    raw.to_csv(log, index=False, float_format="%.17g")
    channel_map = tmp_path / "fs.toml"
    channel_map.write_text(
        '[time]\nsource = "Time_ms"\nunit = "ms"\n'
        '[channels.ax]\nsource = "AccX_g"\nunit = "g"\n'
        '[channels.ay]\nsource = "AccY_g"\nunit = "g"\nsign = -1\n'
        + "".join(
            f'[channels.d_{w}]\nsource = "Pot_{w.upper()}"\nunit = "mm"\nmotion_ratio = 0.8\n'
            for w in WHEELS
        )  # fmt: skip
    )
    signals = read_log(log, channels=channel_map)
    np.testing.assert_allclose(signals.t, si["t"], rtol=1e-12)
    np.testing.assert_allclose(signals.acc[:, :2], si[["ax", "ay"]], rtol=0, atol=1e-9)
    np.testing.assert_allclose(signals.d, si[[f"d_{w}" for w in WHEELS]], rtol=0, atol=1e-9)
    assert signals.az_assumed and signals.mode() == (
        "four travel sensors; no az: g assumed; vx: none (aerodynamic terms off)"
    )


def test_wheel_channels_in_their_own_units_through_a_map(tmp_path):
    """The tyre-force channels through a map: spins in rpm (no radius: a spin, not a
    speed), torques in kN m, the steer angle in degrees, each to SI exactly; rpm on a
    gyro or a radius on a spin is an error naming the key."""
    from wheelload.studies.pipeline.example_log import example_log_path

    si = pd.read_csv(example_log_path())
    n = len(si)
    spin, torque = 60.0 + np.linspace(0.0, 5.0, n), 300.0 * np.sin(np.linspace(0.0, 6.0, n))
    steer = 0.05 * np.sin(np.linspace(0.0, 3.0, n))
    raw = si.copy()
    for w in WHEELS:
        raw[f"Spin_{w}"] = spin * 60.0 / (2.0 * np.pi)
        raw[f"Trq_{w}"] = torque / 1000.0
    raw["Steer_deg"] = np.degrees(steer)
    log = tmp_path / "wheels.csv"
    raw.to_csv(log, index=False, float_format="%.17g")
    same = [c for c in si.columns if c != "t" and not c.startswith("fz_")]
    text = '[time]\nsource = "t"\nunit = "s"\n' + "".join(
        f'[channels.{c}]\nsource = "{c}"\nunit = "{_si_unit(c)}"\n' for c in same
    )
    wheels = (
        "".join(
            f'[channels.omega_{w}]\nsource = "Spin_{w}"\nunit = "rpm"\n'
            f'[channels.torque_{w}]\nsource = "Trq_{w}"\nunit = "kNm"\n'
            for w in WHEELS
        )
        + '[channels.steer]\nsource = "Steer_deg"\nunit = "deg"\n'
    )
    channel_map = tmp_path / "map.toml"
    channel_map.write_text(text + wheels)
    signals = read_log(log, channels=channel_map, wiring_checks=False)
    np.testing.assert_allclose(signals.spin, np.repeat(spin[:, None], 4, axis=1), rtol=1e-12)
    np.testing.assert_allclose(signals.torque, np.repeat(torque[:, None], 4, axis=1),
                               rtol=1e-12, atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(signals.steer, steer, rtol=1e-12, atol=1e-15)
    for edit, message in (
        (('source = "wz"\nunit = "rad/s"', 'source = "wz"\nunit = "rpm"'),
         r"channel 'wz': a rotation speed is for wheel speeds ws_\* and wheel spins omega_\*"),
        (('[channels.omega_fl]\nsource = "Spin_fl"\nunit = "rpm"',
          '[channels.omega_fl]\nsource = "Spin_fl"\nunit = "rpm"\nradius = 0.3'),
         r"channel 'omega_fl': .*keys radius, ratio for ws_\* only"),
        (('unit = "kNm"', 'unit = "kN"'), r"unit 'kN' is a force, the channel needs a torque"),
    ):  # fmt: skip
        channel_map.write_text((text + wheels).replace(*edit, 1))
        with pytest.raises(LogError, match=message):
            read_log(log, channels=channel_map, wiring_checks=False)


def _si_unit(name: str) -> str:
    """The SI unit of one of the log format's channels."""
    from wheelload.estimators.logs.readers.channel_map import TARGETS

    return TARGETS[name].value


def test_erg_with_no_records_has_empty_channels_and_a_partial_record_is_refused(tmp_path):
    """A header-only ERG (a run that logged nothing) reads as channels of no samples; one
    byte short of a whole record is a truncated file, said with its sizes."""
    from wheelload.estimators.logs.readers.channel_map import ChannelMapError
    from wheelload.estimators.logs.readers.erg import read_erg_channels

    path = tmp_path / "empty.erg"
    write_erg(path, {"Time": np.array([]), "IMU_AccX": np.array([])},
              {"Time": "s", "IMU_AccX": "m/s^2"})  # fmt: skip
    (channel,) = read_erg_channels(path, ["IMU_AccX"]).values()
    assert channel.t.size == channel.values.size == 0 and channel.unit == "m/s^2"
    whole = tmp_path / "whole.erg"
    write_erg(whole, {"Time": np.array([0.0, 0.01]), "IMU_AccX": np.array([0.1, 0.2])},
              {"Time": "s", "IMU_AccX": "m/s^2"})  # fmt: skip
    whole.write_bytes(whole.read_bytes()[:-1])
    with pytest.raises(ChannelMapError, match=r"31 data bytes is not a whole number of 16-byte"):
        read_erg_channels(whole, ["IMU_AccX"])
