"""CSV and Parquet logs read as source channels on one time column.

Only the columns a channel map names are read; CSV in chunks of
:data:`CHUNK_ROWS` rows, Parquet by column.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from wheelload.estimators.logs.readers.channel_map import Channel, ChannelMap, ChannelMapError
from wheelload.estimators.logs.readers.formats import CSV_SUFFIXES
from wheelload.estimators.logs.readers.units import Kind, unit_factor

if TYPE_CHECKING:
    import pandas as pd

CHUNK_ROWS = 200_000


def read_table(path: Path, columns: list[str] | None = None) -> pd.DataFrame:
    """The columns of a CSV (``#`` comments, in chunks) or Parquet file."""
    import pandas as pd

    if path.suffix.lower() in CSV_SUFFIXES:
        chunks = pd.read_csv(path, comment="#", usecols=columns, chunksize=CHUNK_ROWS)
        frames = list(chunks)
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=columns)
    return pd.read_parquet(path, columns=columns)


def table_columns(path: Path) -> list[str]:
    """The column names of a CSV or Parquet log."""
    import pandas as pd

    if path.suffix.lower() in CSV_SUFFIXES:
        return [str(c).strip() for c in pd.read_csv(path, comment="#", nrows=0).columns]
    import pyarrow.parquet as pq

    return list(pq.read_schema(path).names)


def read_tabular_channels(path: Path, channel_map: ChannelMap) -> dict[str, Channel]:
    """The mapped columns of a table, each a :class:`Channel` on the time column."""
    import pandas as pd

    if channel_map.time is None:
        raise ChannelMapError(
            f"{channel_map.source}: a CSV or Parquet log needs [time] source = COLUMN"
        )
    present = set(table_columns(path))
    wanted = list(dict.fromkeys(channel_map.sources()))
    for name in wanted:
        if name not in present:
            raise ChannelMapError(
                f"{path}: no column '{name}' (named in {channel_map.source}); "
                f"columns: {', '.join(sorted(present))}"
            )
    frame = read_table(path, wanted)
    time = channel_map.time
    factor = unit_factor(time.unit, Kind.TIME, f"{channel_map.source}: key 'time.unit'")
    t = pd.to_numeric(frame[time.source], errors="coerce").to_numpy(float) * factor
    return {
        name: Channel(t=t, values=pd.to_numeric(frame[name], errors="coerce").to_numpy(float))
        for name in wanted
    } | {time.source: Channel(t=t, values=t)}
