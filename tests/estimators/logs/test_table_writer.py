"""Tables written chunk by chunk on the writer thread: CSV and Parquet give back the same numbers.

The CSV's floats are in shortest round-trip form, so the tolerance between a CSV
read back and the Parquet (binary doubles) is zero: any difference is a bug.
"""

import signal

import numpy as np
import pandas as pd
import pyarrow.csv as pc
import pyarrow.parquet as pq
import pytest

from wheelload.estimators.logs.output_files import OutputError, table_writer
from wheelload.studies.cli import main


def _hard_doubles(n: int, seed: int) -> np.ndarray:
    """Doubles whose text needs care: random bit patterns over every exponent, 17-digit
    values, the smallest subnormal, the largest double, -0.0."""
    rng = np.random.default_rng(seed)
    bits = rng.integers(0, 2**63 - 2**52, size=n, dtype=np.int64)  # finite, positive
    values = bits.view(np.float64) * rng.choice([-1.0, 1.0], size=n)
    values[:6] = [0.1 + 0.2, 1.0 / 3.0, 5e-324, np.finfo(float).max, -0.0, 4229.372052801094]
    return values


def _write_both(folder, chunks):
    paths = folder / "t.csv", folder / "t.parquet"
    for path in paths:
        with table_writer(path) as write:
            for chunk in chunks:
                write(chunk)
    return paths


def test_csv_and_parquet_read_back_the_same_doubles(tmp_path):
    chunks = [
        {"t": np.arange(k * 1000, (k + 1) * 1000) / 100.0, "fz_fl": _hard_doubles(1000, k),
         "status": np.arange(1000, dtype=np.uint32) * np.uint32(4_000_000)}
        for k in range(3)
    ]  # fmt: skip
    csv, parquet = _write_both(tmp_path, chunks)
    binary = pq.read_table(parquet).to_pandas()
    expected = pd.DataFrame({name: np.concatenate([c[name] for c in chunks]) for name in chunks[0]})
    pd.testing.assert_frame_equal(binary, expected, check_exact=True)
    by_arrow = pc.read_csv(csv).to_pandas()
    by_pandas = pd.read_csv(csv)
    for text in (by_arrow, by_pandas):  # tolerance zero: the same doubles, bit for bit
        assert list(text.columns) == list(expected.columns)
        for name in ("t", "fz_fl"):
            assert np.array_equal(text[name].to_numpy(float), expected[name].to_numpy())
            assert np.array_equal(
                np.signbit(text[name].to_numpy(float)), np.signbit(expected[name])
            )
        assert np.array_equal(text["status"].to_numpy(np.int64), expected["status"].to_numpy())


def test_the_estimates_as_csv_and_as_parquet_read_back_equal(tmp_path, capsys):
    csv, parquet = tmp_path / "loads.csv", tmp_path / "loads.parquet"
    for out in (csv, parquet):
        assert main(["estimate", "--example", "--out", str(out)]) == 0
    capsys.readouterr()
    text, binary = pd.read_csv(csv), pd.read_parquet(parquet)
    assert len(binary) > 1000 and list(text.columns) == list(binary.columns)
    # tolerance zero: the CSV's shortest round-trip floats are the Parquet's doubles
    pd.testing.assert_frame_equal(text, binary, check_exact=True, check_dtype=False)


def test_a_writer_error_reaches_the_caller_and_leaves_nothing(tmp_path):
    out = tmp_path / "loads.csv"
    with pytest.raises(OutputError, match="first chunk.s schema"):
        with table_writer(out) as write:
            write({"t": np.arange(3.0), "fz_fl": np.ones(3)})
            write({"t": np.arange(3.0)})  # another set of columns: refused by the writer
    assert list(tmp_path.iterdir()) == []


def test_a_press_an_extension_swallowed_leaves_no_output(tmp_path):
    """Ctrl-C counted by the command line's handler but swallowed by an extension (as
    CasADi's evaluation does) while the table was written: the output is not put in place,
    the temporary is removed, and the press is raised."""
    from wheelload.models.runtime import interrupts

    path = tmp_path / "loads.csv"
    try:
        with pytest.raises(KeyboardInterrupt):
            with table_writer(path) as write:
                write({"t": np.arange(3.0)})
                try:
                    interrupts.handler(signal.SIGINT, None)  # counted, raised ...
                except KeyboardInterrupt:
                    pass  # ... and swallowed
                write({"t": np.arange(3.0, 6.0)})
    finally:
        interrupts.reset()
    assert not path.exists() and list(tmp_path.iterdir()) == []
