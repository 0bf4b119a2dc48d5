"""CSV and Parquet logs read in chunks of rows, as float64 column arrays (pyarrow).

The lean whole-log path (``estimators/kf/log_stream.py``) reads a long log
chunk by chunk so that its memory is bounded by the chunk: Parquet by record
batches (within row groups), CSV by blocks of about :data:`CSV_BLOCK` bytes.
Every value becomes a float64 (a null or empty field is NaN). A file this
reader cannot take as plain numbers (comments, text in a numeric column,
names with surrounding spaces, repeated names) raises :class:`ChunkError`, and
the caller reads it the ordinary way, whose errors name the row and the fix.

Example
-------
>>> for chunk in read_chunks(Path("drive.parquet"), ["t", "ax"], rows=1 << 18):
...     chunk["t"].shape
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from wheelload.estimators.logs.readers.formats import CSV_SUFFIXES, PARQUET_SUFFIXES

#: Bytes per CSV block read at a time.
CSV_BLOCK = 1 << 24
#: Rows per Parquet batch.
PARQUET_ROWS = 1 << 18


class ChunkError(ValueError):
    """The log cannot be read in chunks as plain numbers (read it the ordinary way)."""


def chunk_columns(path: Path) -> list[str]:
    """The column names of a CSV or Parquet log as written in the file."""
    import pyarrow as pa

    try:
        if path.suffix.lower() in PARQUET_SUFFIXES:
            import pyarrow.parquet as pq

            schema = pq.read_schema(path)
            kinds = {name: schema.field(name).type for name in schema.names}
            names = list(schema.names)
            for name, kind in kinds.items():
                if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
                    raise ChunkError(f"{path}: column '{name}' is {kind}, not numbers")
        elif path.suffix.lower() in CSV_SUFFIXES:
            import pyarrow.csv as pc

            with pc.open_csv(path, read_options=pc.ReadOptions(block_size=1 << 16)) as reader:
                names = list(reader.schema.names)
        else:
            raise ChunkError(f"{path}: not a CSV or Parquet log")
    except (pa.ArrowException, OSError, UnicodeDecodeError) as error:
        raise ChunkError(f"{path}: {error}") from None
    if len(set(names)) != len(names) or any(name != name.strip() for name in names):
        raise ChunkError(f"{path}: repeated or padded column names")
    return names


def read_chunks(path: Path, columns: list[str], *, rows: int = PARQUET_ROWS) -> Iterator[dict]:
    """Chunks of at most ``rows`` rows of ``columns`` (present in the file), ``{name: float64}``."""
    import pyarrow as pa

    try:
        if path.suffix.lower() in PARQUET_SUFFIXES:
            import pyarrow.parquet as pq

            # Column pages read as needed, one thread: memory about a batch, not a row group.
            with pq.ParquetFile(path, pre_buffer=False, buffer_size=1 << 20) as source:
                batches = source.iter_batches(batch_size=rows, columns=columns, use_threads=False)
                for batch in batches:
                    yield _floats(batch, columns)
            pa.default_memory_pool().release_unused()  # the decoding buffers, kept otherwise
            return
        import pyarrow.csv as pc

        options = pc.ConvertOptions(
            column_types={name: pa.float64() for name in columns}, include_columns=columns
        )
        with pc.open_csv(
            path, read_options=pc.ReadOptions(block_size=CSV_BLOCK), convert_options=options
        ) as reader:
            for batch in reader:  # blocks of CSV_BLOCK bytes, cut into ``rows``
                for start in range(0, batch.num_rows, rows):
                    yield _floats(batch.slice(start, rows), columns)
        pa.default_memory_pool().release_unused()
    except (pa.ArrowException, OSError, UnicodeDecodeError) as error:
        raise ChunkError(f"{path}: {error}") from None


def _floats(batch, columns: list[str]) -> dict:
    import pyarrow as pa

    result = {}
    for name in columns:
        array = batch.column(name)
        if array.type != pa.float64():  # float16/32, (u)int8-64: exact in float64 but int64
            array = array.cast(pa.float64(), safe=False)
        result[name] = float_values(array)
    return result


def float_values(array) -> np.ndarray:
    """A float64 arrow array as numpy, nulls as NaN: what ``to_numpy`` gives (a read-only
    view without nulls, a copy with them), without the pandas import ``to_numpy`` makes."""
    n, offset = len(array), array.offset
    validity, data = array.buffers()
    if data is None:  # no value buffer (all null)
        return np.full(n, np.nan)
    values = np.frombuffer(data, dtype=np.float64, count=n, offset=8 * offset)
    if array.null_count == 0:
        values.flags.writeable = False  # a view of arrow's memory, as to_numpy's
        return values
    values = values.copy()
    bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
    values[bits[offset : offset + n] == 0] = np.nan
    return values
