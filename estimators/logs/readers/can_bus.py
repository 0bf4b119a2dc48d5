"""CAN bus logs decoded with a DBC: MDF4 bus logging, Vector BLF and ASC.

Each DBC signal a channel map names becomes a source channel with the time
stamps of the frames that carry it (a multiplexed signal: of the frames whose
multiplexor selects it) and its physical values (factor and offset applied) in
the DBC's unit:

- MDF4 (``.mf4``) with raw ``CAN_DataFrame`` channels: asammdf's
  ``MDF.extract_bus_logging`` with the DBC;
- Vector BLF (``.blf``) and ASC (``.asc``): frames read by ``python-can``, decoded
  by ``cantools``; time stamps from the start of the measurement.

A frame the map needs that never appears in the log is a one-line error naming
the frame, its signal and the channel it is for.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wheelload.estimators.logs.readers.channel_map import Channel, ChannelMap, ChannelMapError
from wheelload.estimators.logs.readers.dbc import DbcSignal, dbc_signals, load_dbc
from wheelload.estimators.logs.readers.formats import CAN_SUFFIXES, MDF_SUFFIXES

SUFFIXES = CAN_SUFFIXES
#: The channel of raw CAN frames in an MDF4 bus logging file (ASAM MDF 4.1 bus logging).
RAW_FRAMES = "CAN_DataFrame"


def needs_dbc(path: Path, source: str) -> ChannelMapError:
    """The error for a CAN log read without a DBC: name the file and the fix."""
    raw = "" if path.suffix.lower() in SUFFIXES else f" ({RAW_FRAMES})"
    return ChannelMapError(
        f"{path}: holds raw CAN frames{raw}: give the DBC that decodes them, "
        f'dbc = "car.dbc" at the top of the channel map ({source})'
    )


def read_can_channels(path: Path, channel_map: ChannelMap) -> dict[str, Channel]:
    """The DBC signals the channel map names, each a :class:`Channel` (see module doc)."""
    if channel_map.dbc is None:
        raise needs_dbc(path, channel_map.source)
    if path.suffix.lower() not in (*SUFFIXES, *MDF_SUFFIXES):
        raise ChannelMapError(
            f"{path}: the key 'dbc' of {channel_map.source} decodes CAN logs "
            f"({', '.join((*MDF_SUFFIXES, *SUFFIXES))}): leave it out for this log"
        )
    database = load_dbc(channel_map.dbc)
    signals = dbc_signals(database, [s.source for s in channel_map.channels.values()],
                          channel_map.dbc)  # fmt: skip
    if path.suffix.lower() in SUFFIXES:
        channels = _vector_log(path, database, signals)
    else:
        channels = _bus_logging(path, channel_map.dbc, signals)
    for name, spec in channel_map.channels.items():
        if channels[spec.source].t.size == 0:
            signal = signals[spec.source]
            raise ChannelMapError(
                f"{path}: frame '{signal.frame}' (0x{signal.frame_id:X}) never appears, so "
                f"signal '{spec.source}' (for '{name}') has no sample: log that frame, or "
                f"leave '{name}' out of {channel_map.source}"
            )
    return channels


def _vector_log(path: Path, database, signals: dict[str, DbcSignal]) -> dict[str, Channel]:
    """Decode the frames of a BLF or ASC file that carry the wanted signals."""
    import can

    ids = {signal.frame_id for signal in signals.values()}
    stamps: dict[int, list[float]] = {i: [] for i in ids}
    payloads: dict[int, list[bytes]] = {i: [] for i in ids}
    try:
        if path.suffix.lower() == ".blf":
            reader = can.BLFReader(path)
            start = float(reader.start_timestamp or 0.0)
        else:
            reader, start = can.ASCReader(path, relative_timestamp=True), 0.0
        for message in reader:
            if message.is_error_frame or message.is_remote_frame:
                continue
            if message.arbitration_id in stamps:
                stamps[message.arbitration_id].append(message.timestamp - start)
                payloads[message.arbitration_id].append(bytes(message.data))
    except (OSError, ValueError, can.CanError) as error:
        raise ChannelMapError(
            f"{path}: not a readable {path.suffix.lower()[1:].upper()} file "
            f"({type(error).__name__}: {error}): export it again from the logger software"
        ) from None
    decoded: dict[str, tuple[list[float], list[float]]] = {name: ([], []) for name in signals}
    for frame_id in ids:
        message = database.get_message_by_frame_id(frame_id)
        wanted = [(n, s.name) for n, s in signals.items() if s.frame_id == frame_id]
        for stamp, data in zip(stamps[frame_id], payloads[frame_id]):
            try:
                values = message.decode(data, decode_choices=False, allow_truncated=True)
            except Exception:  # a frame the DBC cannot decode (a wrong length): no sample
                continue
            for name, signal in wanted:
                if signal in values:  # a multiplexed signal: only in frames selecting it
                    decoded[name][0].append(stamp)
                    decoded[name][1].append(float(values[signal]))
    return {name: _channel(*decoded[name], signals[name].unit) for name in signals}


def _channel(t: list[float], values: list[float], unit: str) -> Channel:
    """A channel with its samples in time order (a log may hold frames out of order)."""
    t_array, v_array = np.asarray(t, float), np.asarray(values, float)
    order = np.argsort(t_array, kind="stable")
    return Channel(t=t_array[order], values=v_array[order], unit=unit)


def _bus_logging(path: Path, dbc: Path, signals: dict[str, DbcSignal]) -> dict[str, Channel]:
    """Decode an MDF4 bus logging file with asammdf's ``extract_bus_logging``."""
    from wheelload.estimators.logs.readers.mdf import open_mdf

    channels = {}
    with open_mdf(path) as mdf:
        if RAW_FRAMES not in mdf.channels_db:
            raise ChannelMapError(
                f"{path}: has no raw CAN frames ({RAW_FRAMES}) to decode with the DBC: "
                "leave the key 'dbc' out of the channel map and name the file's channels"
            )
        extracted = mdf.extract_bus_logging({"CAN": [(str(dbc), 0)]})
        try:
            for name, signal in signals.items():
                key = f"{signal.frame}.{signal.name}"
                if key not in extracted.channels_db:
                    channels[name] = Channel(t=np.zeros(0), values=np.zeros(0), unit=signal.unit)
                    continue
                decoded = extracted.get(key, *extracted.channels_db[key][0])
                channels[name] = _channel(decoded.timestamps, decoded.samples, signal.unit)
        finally:
            extracted.close()
    return channels
