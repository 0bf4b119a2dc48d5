"""ASAM MDF4 (``.mf4``, ``.mdf``) logs through ``asammdf``.

Each channel keeps its own time stamps and declared unit; values are the
physical values of the file's conversion rules. Only the channels a channel
map names are read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wheelload.estimators.readers.channel_map import Channel, ChannelMapError

SUFFIXES = (".mf4", ".mdf", ".dat")


def mdf_channel_names(path: Path) -> list[str]:
    """Names of the channels in an MDF file (time channels left out)."""
    from asammdf import MDF

    with MDF(path) as mdf:
        return sorted(name for name in mdf.channels_db if name.lower() not in ("t", "time"))


def read_mdf_channels(path: Path, names: list[str]) -> dict[str, Channel]:
    """The named channels of an MDF file with their time stamps and units."""
    from asammdf import MDF

    channels = {}
    try:
        mdf_file = MDF(path)
    except Exception as error:  # asammdf raises many kinds for a damaged file
        raise ChannelMapError(f"{path}: not a readable MDF file: {error}") from None
    with mdf_file as mdf:
        for name in dict.fromkeys(names):
            if name not in mdf.channels_db:
                raise ChannelMapError(
                    f"{path}: no channel '{name}'; the file has "
                    f"{', '.join(mdf_channel_names(path)[:30])}"
                )
            if len(mdf.channels_db[name]) > 1:
                raise ChannelMapError(
                    f"{path}: channel '{name}' is in {len(mdf.channels_db[name])} channel groups; "
                    "export one of them under its own name"
                )
            signal = mdf.get(name)
            channels[name] = Channel(
                t=np.asarray(signal.timestamps, float),
                values=np.asarray(signal.samples, float),
                unit=str(signal.unit or ""),
            )
    return channels
