"""CAN logs decoded with the CAN car's DBC: real MDF4 bus logging (asammdf), BLF and ASC
(python-can) files on disk, read through channel maps.

The frames are written by :mod:`wheelload.studies.drive.can_car` from a smooth synthetic
log without jitter, so each frame's send time is its stamp minus its frame latency and
each decoded value is the source at that time, rounded to the DBC's step: a decoded
value must be within half a step (plus 1e-9 of rounding) of the source. Time stamps:
MDF4 keeps float64 seconds (1e-9 s); BLF and ASC keep them from an absolute start
(2026-01-01) in ns and us, whose float64 sum is good to 1e-6 s.
"""

import math

import cantools
import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import LogError, read_log
from wheelload.estimators.logs.readers import load_channel_map
from wheelload.estimators.logs.readers.can_bus import read_can_channels
from wheelload.estimators.logs.readers.frames import read_frame
from wheelload.models.conventions import WHEELS
from wheelload.studies.drive.can_car import (
    LATENCIES,
    PERIODS,
    SIGNALS,
    TO_UNIT,
    UNION_CLOCK,
    CanCar,
    CanFrames,
    can_frames,
    channel_map_text,
    dbc_path,
    write_bus_logging,
    write_vector_log,
)

DURATION, RATE = 3.0, 200.0
STAMP_TOLERANCE = {".mf4": 1e-9, ".blf": 1e-6, ".asc": 1e-6}
NO_JITTER = CanCar(jitter=0.0)


def _source() -> pd.DataFrame:
    """A smooth log of every channel the CAN car sends, within the DBC's ranges."""
    t = np.arange(int(DURATION * RATE) + 1) / RATE
    wave = lambda f, a, c=0.0: c + a * np.sin(2 * np.pi * f * t + f)  # noqa: E731
    log = {"t": t, "vx": wave(0.3, 2.0, 20.0), "ax": wave(0.7, 3.0), "ay": wave(0.5, 8.0),
           "az": wave(1.1, 1.0, 9.81), "wx": wave(0.9, 0.2), "wy": wave(1.3, 0.1),
           "wz": wave(0.4, 0.5), "steer": wave(0.4, 0.05)}  # fmt: skip
    for k, w in enumerate(WHEELS):
        log[f"d_{w}"] = wave(1.5 + k, 0.03)
        log[f"fz_{w}"] = wave(0.8 + k, 1500.0, 4000.0)
    return pd.DataFrame(log)


@pytest.fixture(scope="module")
def can_logs(tmp_path_factory):
    """The synthetic log as MF4, BLF and ASC files, its two channel maps and the frames."""
    folder = tmp_path_factory.mktemp("can")
    frames = can_frames(_source(), NO_JITTER)
    write_bus_logging(frames, folder / "drive.mf4")
    write_vector_log(frames, folder / "drive.blf")
    write_vector_log(frames, folder / "drive.asc")
    (folder / "plain.toml").write_text(channel_map_text(str(dbc_path())))
    (folder / "latency.toml").write_text(channel_map_text(str(dbc_path()), LATENCIES))
    return folder, frames


def _step(signal: str) -> float:
    database = cantools.database.load_file(dbc_path())
    (scale,) = {s.scale for m in database.messages for s in m.signals if s.name == signal}
    return float(scale)


@pytest.mark.parametrize("suffix", [".mf4", ".blf", ".asc"])
def test_every_signal_decodes_to_the_source_at_its_send_time(can_logs, suffix):
    folder, _ = can_logs
    source = _source()
    channel_map = load_channel_map(folder / "plain.toml")
    channels = read_can_channels(folder / f"drive{suffix}", channel_map)
    for name, (frame, signal, unit) in SIGNALS.items():
        if name.startswith("ws_"):
            continue  # the wheel speeds are vx (the source has no wheel spins)
        channel = channels[signal]
        send = channel.t - LATENCIES[frame]
        period = PERIODS[frame] * (4 if frame == "WheelForce" else 1)  # one corner a frame
        start = WHEELS.index(name[3:]) * PERIODS[frame] if frame == "WheelForce" else 0.0
        expected_send = source.t[0] + start + period * np.arange(send.size)
        assert np.max(np.abs(send - expected_send)) < STAMP_TOLERANCE[suffix], name
        expected = np.interp(send, source.t, source[name]) * TO_UNIT[unit]
        assert np.max(np.abs(channel.values - expected)) <= 0.5 * _step(signal) + 1e-9, name
        assert channel.unit == unit


def test_multiplexed_loads_come_one_corner_per_frame(can_logs):
    folder, frames = can_logs
    channels = read_can_channels(folder / "drive.blf", load_channel_map(folder / "plain.toml"))
    force_frames = int(np.sum(frames.frame_id == 0x500))
    counts = [channels[f"Fz{w.upper()}"].t.size for w in WHEELS]
    assert sum(counts) == force_frames and max(counts) - min(counts) <= 1


def test_latency_key_shifts_a_channel_back_to_its_send_times(can_logs):
    folder, _ = can_logs
    frame = read_frame(folder / "drive.mf4", load_channel_map(folder / "latency.toml"))
    send = _source().t[0] + PERIODS["IMU_Acc"] * np.arange(len(frame))
    assert np.max(np.abs(frame["t"].to_numpy() - send)) < 1e-9  # the clock: ax's stamps
    late = read_frame(folder / "drive.mf4", load_channel_map(folder / "plain.toml"))
    shift = late["t"].to_numpy() - frame["t"].to_numpy()
    assert np.allclose(shift, LATENCIES["IMU_Acc"], atol=1e-9)


def test_union_table_holds_each_channel_at_its_own_stamps(can_logs):
    folder, frames = can_logs
    text = channel_map_text(str(dbc_path()), LATENCIES, UNION_CLOCK)
    (folder / "union.toml").write_text(text)
    table = read_frame(folder / "drive.mf4", load_channel_map(folder / "union.toml"))
    per_frame = {f: int(np.sum(frames.frame_id == i)) for f, i in
                 (("IMU_Acc", 0x120), ("Dampers", 0x200), ("WheelSpeeds", 0x300))}  # fmt: skip
    assert table["ax"].notna().sum() == per_frame["IMU_Acc"]
    assert table["d_fl"].notna().sum() == per_frame["Dampers"]
    assert table["ws_rr"].notna().sum() == per_frame["WheelSpeeds"]
    assert (table["ay"].notna() == table["ax"].notna()).all()  # one frame, one row
    assert np.all(np.diff(table["t"]) > 0)
    assert table.drop(columns="t").notna().any(axis=1).all()  # no row without a sample


def test_out_of_order_frames_read_as_the_ordered_ones(can_logs, tmp_path):
    folder, frames = can_logs
    shuffled = can_frames(_source(), CanCar(jitter=0.0, reorder=True))
    assert np.any(np.diff(shuffled.t) < 0)  # the file holds frames out of order
    write_vector_log(shuffled, tmp_path / "shuffled.blf")
    write_bus_logging(shuffled, tmp_path / "shuffled.mf4")
    channel_map = load_channel_map(folder / "latency.toml")
    for suffix in (".blf", ".mf4"):  # the same stamps and values, bit for bit
        ordered = read_frame(folder / f"drive{suffix}", channel_map)
        again = read_frame(tmp_path / f"shuffled{suffix}", channel_map)
        assert np.array_equal(again.to_numpy(), ordered.to_numpy(), equal_nan=True)


def test_read_log_gives_si_signals(can_logs):
    folder, _ = can_logs
    signals = read_log(folder / "drive.blf", channels=folder / "latency.toml")
    source = _source()
    at = lambda name: np.interp(signals.t, source.t, source[name])  # noqa: E731
    # 100 Hz travel interpolated onto the 200 Hz clock: half the DBC's 5 um step plus the
    # linear interpolation's error, A w^2 h^2 / 8 = 0.03 (2 pi 1.5)^2 0.01^2 / 8 = 33 um.
    assert np.nanmax(np.abs(signals.d[:, 0] - at("d_fl"))) < 4e-5
    # az on its own stamps (the clock): half the DBC's step of 1e-4 g, in m/s^2.
    assert np.nanmax(np.abs(signals.acc[:, 2] - at("az"))) < 0.5e-4 * 9.80665 + 1e-9
    assert math.isclose(np.nanmedian(signals.vx), 20.0, abs_tol=0.1)


def _one_line_error(path, channels):
    with pytest.raises(LogError) as error:
        read_log(path, channels=channels, wiring_checks=False)
    message = str(error.value)
    assert "\n" not in message
    return message


def test_a_frame_that_never_appears_is_named(can_logs, tmp_path):
    folder, frames = can_logs
    keep = frames.frame_id != 0x200
    write_vector_log(CanFrames(t=frames.t[keep], frame_id=frames.frame_id[keep],
                               data=frames.data[keep]), tmp_path / "no_dampers.blf")  # fmt: skip
    message = _one_line_error(tmp_path / "no_dampers.blf", folder / "plain.toml")
    assert "frame 'Dampers' (0x200) never appears" in message
    assert "'TravelFL' (for 'd_fl')" in message and "leave 'd_fl' out" in message


def test_raw_frames_without_a_dbc_say_to_give_one(can_logs, tmp_path):
    folder, _ = can_logs
    (tmp_path / "no_dbc.toml").write_text(
        (folder / "plain.toml").read_text().replace(f'dbc = "{dbc_path()}"', "")
    )
    for channels in (tmp_path / "no_dbc.toml", None):
        message = _one_line_error(folder / "drive.mf4", channels)
        assert "raw CAN frames (CAN_DataFrame)" in message and 'dbc = "car.dbc"' in message
    assert 'dbc = "car.dbc"' in _one_line_error(folder / "drive.blf", None)


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (("[channels.ay]\n", "[channels.ay]\nlatency = -0.1\n"), "'channels.ay.latency' must be"),
        (("[channels.ay]\n", "[channels.ay]\nlatency = 300\n"), "not milliseconds"),
        (('source = "AccY"', 'source = "AccQ"'), "no signal 'AccQ' in the DBC"),
        (("can_car.dbc", "nowhere.dbc"), "no such DBC file"),
    ],
)
def test_map_mistakes_are_one_line(can_logs, tmp_path, edit, expected):
    folder, _ = can_logs
    (tmp_path / "map.toml").write_text((folder / "plain.toml").read_text().replace(*edit))
    assert expected in _one_line_error(folder / "drive.mf4", tmp_path / "map.toml")


def test_a_dbc_key_on_a_table_log_is_refused(can_logs, tmp_path):
    folder, _ = can_logs
    _source().to_csv(tmp_path / "drive.csv", index=False)
    message = _one_line_error(tmp_path / "drive.csv", folder / "plain.toml")
    assert "decodes CAN logs" in message


def test_an_even_clock_takes_jittering_stamps(can_logs, tmp_path):
    """A logger's jitter (0.2 ms, 4 % of the IMU's period) onto ``[clock] rate = 200``:
    even steps (to 1e-12 s), and ax as on the jitter-free log within its slope times the
    jitter (A w = 3 * 2 pi 0.7 m/s^3 times 1 ms, five standard deviations of the seeded
    draw) plus a DBC step."""
    folder, _ = can_logs
    rough = can_frames(_source(), CanCar(jitter=200e-6))
    write_bus_logging(rough, tmp_path / "rough.mf4")
    channel_map = load_channel_map(folder / "latency.toml")
    assert channel_map.clock.rate == 200.0
    table = read_frame(tmp_path / "rough.mf4", channel_map)
    assert np.max(np.abs(np.diff(table["t"]) - 0.005)) < 1e-12
    still = read_frame(folder / "drive.mf4", channel_map)
    rows = min(len(table), len(still)) - 1
    assert (
        np.nanmax(np.abs(table["ax"][:rows] - still["ax"][:rows]))
        < 3 * 2 * np.pi * 0.7 * 1e-3 + 0.001
    )


def test_union_and_rate_exclude_each_other(can_logs, tmp_path):
    folder, _ = can_logs
    text = channel_map_text(str(dbc_path()), LATENCIES, ("union = true", "rate = 200"))
    (tmp_path / "both.toml").write_text(text)
    message = _one_line_error(folder / "drive.mf4", tmp_path / "both.toml")
    assert "'clock.union' and 'clock.rate' exclude each other" in message
