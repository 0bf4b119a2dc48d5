"""A DBC file's signals, and which frame carries each (``cantools``).

The channel map names DBC signals as sources (``source = "AccY"``, or
``"IMU_Acc.AccY"`` when two frames carry a signal of that name). Scaled signals
(factor, offset) and multiplexed ones (a multiplexor signal selects which of
them a frame carries) are decoded to their physical values in the DBC's unit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from wheelload.estimators.logs.readers.channel_map import ChannelMapError


@dataclass(frozen=True, kw_only=True)
class DbcSignal:
    """One DBC signal a channel map reads: its frame and its declared unit."""

    name: str  # the signal's name in the DBC
    frame: str  # the frame (message) name
    frame_id: int
    unit: str


def load_dbc(path: Path):
    """The ``cantools`` database of a DBC file, or a one-line :class:`ChannelMapError`."""
    import cantools

    if not path.is_file():
        raise ChannelMapError(
            f"{path}: no such DBC file (key 'dbc' of the channel map, relative to the map)"
        )
    try:
        return cantools.database.load_file(path, database_format="dbc", strict=False)
    except Exception as error:  # cantools raises its parse errors under several types
        first = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ChannelMapError(f"{path}: not a readable DBC file ({first})") from None


def dbc_signals(database, names: list[str], dbc: Path) -> dict[str, DbcSignal]:
    """The DBC signals named ``SIGNAL`` or ``FRAME.SIGNAL``; a name not in the DBC, or
    in two frames, is a one-line error naming it and the fix."""
    carriers: dict[str, list] = {}
    for message in database.messages:
        for signal in message.signals:
            carriers.setdefault(signal.name, []).append((message, signal))
            carriers.setdefault(f"{message.name}.{signal.name}", []).append((message, signal))
    found = {}
    for name in dict.fromkeys(names):
        if name not in carriers:
            known = sorted(s.name for m in database.messages for s in m.signals)
            raise ChannelMapError(
                f"{dbc}: no signal '{name}' in the DBC; its signals: {', '.join(known[:40])}"
            )
        if len(carriers[name]) > 1:
            frames = ", ".join(message.name for message, _ in carriers[name])
            raise ChannelMapError(
                f"{dbc}: signal '{name}' is in frames {frames}: give FRAME.{name} as its source"
            )
        ((message, signal),) = carriers[name]
        found[name] = DbcSignal(
            name=signal.name, frame=message.name, frame_id=message.frame_id,
            unit=str(signal.unit or ""),
        )  # fmt: skip
    return found
