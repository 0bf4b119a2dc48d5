"""Logs read in chunks (estimators/logs/readers/chunks.py) against pandas' reading of the
same files: values equal to the bit (float64 both ways), chunk sizes as asked."""

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from wheelload.estimators.logs.readers.chunks import (
    ChunkError,
    chunk_columns,
    float_values,
    read_chunks,
)


@pytest.fixture(scope="module")
def frame():
    rng = np.random.default_rng(2)
    frame = pd.DataFrame({"t": 0.01 * np.arange(50), "ax": rng.normal(size=50),
                          "d_fl": rng.normal(size=50) * 1e-3})  # fmt: skip
    frame.loc[[3, 17, 40], "ax"] = np.nan
    return frame


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_chunks_of_seven_rows_equal_the_whole_file(frame, tmp_path, suffix):
    path = tmp_path / f"log{suffix}"
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path, index=False)
    assert chunk_columns(path) == ["t", "ax", "d_fl"]
    chunks = list(read_chunks(path, ["t", "ax"], rows=7))
    assert [len(c["t"]) for c in chunks] == [7] * 7 + [1]
    for name in ("t", "ax"):
        joined = np.concatenate([c[name] for c in chunks])
        np.testing.assert_array_equal(joined, frame[name].to_numpy())
        assert joined.dtype == np.float64
    assert all(set(c) == {"t", "ax"} for c in chunks)


def test_integer_and_float32_parquet_columns_are_exact_float64(tmp_path):
    table = pa.table({"t": pa.array([0, 1, 2**40], pa.int64()),
                      "ax": pa.array([0.5, -1.25, 3.0], pa.float32())})  # fmt: skip
    path = tmp_path / "log.parquet"
    pq.write_table(table, path)
    (chunk,) = read_chunks(path, ["t", "ax"])
    np.testing.assert_array_equal(chunk["t"], [0.0, 1.0, 2.0**40])
    np.testing.assert_array_equal(chunk["ax"], [0.5, -1.25, 3.0])


def test_what_cannot_be_read_in_chunks_says_so(tmp_path):
    text = tmp_path / "log.parquet"
    pq.write_table(pa.table({"t": [0.0, 0.01], "note": ["a", "b"]}), text)
    with pytest.raises(ChunkError, match="column 'note' is string, not numbers"):
        chunk_columns(text)
    other = tmp_path / "log.mf4"
    other.write_bytes(b"MDF     ")
    with pytest.raises(ChunkError, match="not a CSV or Parquet log"):
        chunk_columns(other)
    for text in ("t,ax,ax\n0,1,2\n", "t, ax\n0,1\n"):
        names = tmp_path / "names.csv"
        names.write_text(text)
        with pytest.raises(ChunkError, match="repeated or padded column names"):
            chunk_columns(names)


def test_float_values_of_a_sliced_array_with_nulls():
    array = pa.array([1.0, None, 3.0, 4.0, None, 6.0], pa.float64()).slice(1, 4)
    np.testing.assert_array_equal(float_values(array), [np.nan, 3.0, 4.0, np.nan])
    plain = float_values(pa.array([1.0, 2.0]).slice(1))
    np.testing.assert_array_equal(plain, [2.0])
    assert not plain.flags.writeable
    np.testing.assert_array_equal(float_values(pa.array([None, None], pa.float64())),
                                  [np.nan, np.nan])  # fmt: skip
