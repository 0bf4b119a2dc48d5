"""A log of any format read as our columns on one clock (:func:`read_frame`).

MDF4, ERG and the CSV exports of logger software (AiM, MoTeC: :mod:`.logger_csv`) carry
each channel's time stamps and unit; CAN logs are decoded with the map's DBC
(:mod:`.can_bus`); other CSV and Parquet logs are tables on one time column
(:mod:`.tabular`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from wheelload.estimators.logs.readers import can_bus, erg, logger_csv, mdf, tabular
from wheelload.estimators.logs.readers.channel_map import (
    ChannelMap,
    ChannelMapError,
    apply_channel_map,
    identity_map,
)
from wheelload.estimators.logs.readers.formats import SUFFIXES

if TYPE_CHECKING:
    import pandas as pd


def _kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ChannelMapError(f"{path}: unknown log format '{suffix}' (use {', '.join(SUFFIXES)})")
    return suffix


def channel_names(path: str | Path) -> list[str]:
    """The source channel names of a log of any supported format."""
    path = Path(path)
    suffix = _kind(path)
    if suffix in mdf.SUFFIXES:
        return mdf.mdf_channel_names(path)
    if suffix in erg.SUFFIXES:
        return erg.erg_channel_names(path)
    if suffix in can_bus.SUFFIXES:
        raise can_bus.needs_dbc(path, "--channels MAP")
    export = logger_csv.logger_export(path)
    if export is not None:
        return [name for name in export.names if name != logger_csv.TIME]
    return tabular.table_columns(path)


def read_frame(path: str | Path, channel_map: ChannelMap | None) -> pd.DataFrame:
    """Our columns of a log on one clock; ``None`` maps channels named as ours, in SI."""
    path = Path(path)
    suffix = _kind(path)
    if suffix in can_bus.SUFFIXES or (channel_map is not None and channel_map.dbc is not None):
        if channel_map is None:
            raise can_bus.needs_dbc(path, "--channels MAP")
        return apply_channel_map(
            can_bus.read_can_channels(path, channel_map), channel_map, str(path)
        )
    export = logger_csv.logger_export(path)
    if suffix in mdf.SUFFIXES or suffix in erg.SUFFIXES or export is not None:
        if suffix in mdf.SUFFIXES:
            _refuse_raw_frames(path, channel_map)
        if channel_map is None:
            channel_map = identity_map(channel_names(path), str(path))
        names = [spec.source for spec in channel_map.channels.values()]
        if export is not None:
            raw = logger_csv.read_export_channels(path, export, names)
        else:
            read = mdf.read_mdf_channels if suffix in mdf.SUFFIXES else erg.read_erg_channels
            raw = read(path, names)
    elif channel_map is None:
        return tabular.read_table(path)
    else:
        raw = tabular.read_tabular_channels(path, channel_map)
    return apply_channel_map(raw, channel_map, str(path))


def _refuse_raw_frames(path: Path, channel_map: ChannelMap | None) -> None:
    """An MDF4 of raw CAN frames read without a DBC: one line that says to give one."""
    names = set(mdf.mdf_channel_names(path))
    if can_bus.RAW_FRAMES not in names:
        return
    wanted = ["ax"] if channel_map is None else channel_map.sources()
    if any(name not in names for name in wanted):
        raise can_bus.needs_dbc(path, channel_map.source if channel_map else "--channels MAP")
