"""Issue 21, item 5: readers that never trace back, on real files through the command line.

Each damaged or unusual file is written for real (pandas/pyarrow Parquet, MF4
with asammdf then cut or overwritten, ERG with ``write_erg`` then cut or
re-headed, channel maps on disk) and run through ``wheelload estimate``: a
file we cannot use is one line on stderr naming the file (and channel or
key) and the fix, exit code 2, no traceback; a file we can use gives the same
estimates on the chunked and the in-memory path.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.logs.readers.chunks import read_chunks
from wheelload.estimators.logs.readers.erg import read_erg_channels, write_erg
from wheelload.estimators.logs.signals import read_log, travel_quantum
from wheelload.models import example_vehicle_path
from wheelload.models.conventions import WHEELS
from wheelload.studies.cli import main
from wheelload.studies.pipeline.example_log import example_log_path

FLOATS = ("float16", "float32", "float64")
INTEGERS = ("int8", "int16", "int32", "int64", "uint8", "uint16", "uint32", "uint64")


def estimate(capsys, path, *extra) -> tuple[int, str, str]:
    code = main(["estimate", str(path), "--vehicle", str(example_vehicle_path()), *extra])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def refused(capsys, path, *extra) -> str:
    """The one line of a refused log (exit code 2, no traceback)."""
    code, _, err = estimate(capsys, path, *extra)
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err and "Exception ignored" not in err, err
    return err


def example_frame() -> pd.DataFrame:
    return pd.read_csv(example_log_path())


def typed_log(dtype: str) -> pd.DataFrame:
    """The example log with every column in a float ``dtype``, or with ``vx`` in an
    integer one (a speed logged in whole m/s; the other channels need fractions)."""
    frame = example_frame()
    if dtype in FLOATS:
        return frame.astype(dtype)
    return frame.assign(vx=frame["vx"].round().astype(dtype))


@pytest.mark.parametrize("dtype", FLOATS + INTEGERS)
def test_read_chunks_takes_every_numeric_parquet_dtype(tmp_path, dtype):
    """Every column comes back as float64 equal to numpy's conversion of the stored values
    (exact: each of these dtypes but (u)int64 converts exactly, and the values here are
    small integers)."""
    values = {"a": np.arange(300) % 100, "b": (np.arange(300) * 7) % 120}
    frame = pd.DataFrame({name: column.astype(dtype) for name, column in values.items()})
    path = tmp_path / "typed.parquet"
    frame.to_parquet(path, index=False)
    chunks = list(read_chunks(path, ["a", "b"], rows=128))
    assert [len(chunk["a"]) for chunk in chunks] == [128, 128, 44]
    for name in ("a", "b"):
        got = np.concatenate([chunk[name] for chunk in chunks])
        assert got.dtype == np.float64
        np.testing.assert_array_equal(got, frame[name].to_numpy().astype(np.float64))


@pytest.mark.parametrize("dtype", FLOATS + INTEGERS)
def test_a_parquet_log_of_any_dtype_gives_the_same_loads_on_both_paths(tmp_path, capsys, dtype):
    """The chunked (default) and in-memory paths agree to the bit, as they do on float64.
    Only notes may be said: a float16 time column steps by one or two of its own quanta
    (2^-7 s beyond 8 s), which both paths read as gaps and say so; a first build says so."""
    path = tmp_path / f"drive_{dtype}.parquet"
    typed_log(dtype).to_parquet(path, index=False)
    outputs = {}
    for mode, extra in (("chunked", ()), ("in-memory", ("--in-memory",))):
        out = tmp_path / f"{mode}.csv"
        code, _, err = estimate(capsys, path, "--out", str(out), *extra)
        assert code == 0 and all(": note: " in line for line in err.splitlines()), err
        assert dtype == "float16" or "gap" not in err, err
        outputs[mode] = pd.read_csv(out)
    pd.testing.assert_frame_equal(outputs["chunked"], outputs["in-memory"], check_exact=True)


def test_a_float32_log_gives_the_float64_loads_within_its_rounding(tmp_path, capsys):
    """float32 keeps 7 digits: travel to 1e-9 m, az to 1e-6 m/s^2; the loads move by far
    less than 1 N (tolerance 1 N: 1e-4 of a wheel load, well above the rounding's effect)."""
    loads = {}
    for dtype in ("float64", "float32"):
        path, out = tmp_path / f"{dtype}.parquet", tmp_path / f"{dtype}.csv"
        typed_log(dtype).to_parquet(path, index=False)
        assert estimate(capsys, path, "--out", str(out))[0] == 0
        loads[dtype] = pd.read_csv(out)[[f"fz_{w}" for w in WHEELS]].to_numpy()
    assert np.max(np.abs(loads["float32"] - loads["float64"])) < 1.0


def write_mf4(path, frame: pd.DataFrame, stamps: dict | None = None) -> None:
    from asammdf import MDF, Signal

    stamps = stamps or {}
    t = frame["t"].to_numpy()
    mdf = MDF(version="4.10")
    for name in frame.columns.drop("t"):
        mdf.append([Signal(frame[name].to_numpy(), stamps.get(name, t), name=name)])
    mdf.save(path, overwrite=True)
    mdf.close()


@pytest.fixture(scope="module")
def mf4_bytes(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("mf4") / "drive.mf4"
    write_mf4(path, example_frame()[["t", "vx", "ax", "ay", "az", "d_fl", "d_fr", "d_rl", "d_rr"]])
    return path.read_bytes()


def test_a_whole_mf4_log_is_estimated(tmp_path, capsys, mf4_bytes):
    path = tmp_path / "drive.mf4"
    path.write_bytes(mf4_bytes)
    code, out, err = estimate(capsys, path)
    assert code == 0 and err == "" and "wiring checks" in out, err


@pytest.mark.parametrize("fraction", [0.02, 0.3, 0.5, 0.7, 0.9, 0.99])
def test_a_truncated_mf4_is_one_line_without_asammdf_traceback(
    tmp_path, capsys, mf4_bytes, fraction
):
    path = tmp_path / "cut.mf4"
    path.write_bytes(mf4_bytes[: int(fraction * len(mf4_bytes))])
    err = refused(capsys, path)
    assert f"{path}: not a readable MDF file" in err and "export it again" in err


@pytest.mark.parametrize("start", [0, 64])
def test_a_corrupt_mf4_block_is_one_line(tmp_path, capsys, mf4_bytes, start):
    data = bytearray(mf4_bytes)
    data[start : start + 512] = bytes(512)  # identification or header blocks zeroed
    path = tmp_path / "corrupt.mf4"
    path.write_bytes(bytes(data))
    err = refused(capsys, path)
    assert f"{path}: not a readable MDF file" in err


def test_a_non_clock_mf4_channel_whose_stamps_go_back_is_named_with_its_sample(tmp_path, capsys):
    frame = example_frame()[["t", "vx", "ax", "ay", "az", "d_fl", "d_fr", "d_rl", "d_rr"]]
    t = frame["t"].to_numpy().copy()
    stamps = t.copy()
    stamps[600:] -= 2.0  # a logger clock reset in the middle of the d_rl channel
    path = tmp_path / "reset.mf4"
    write_mf4(path, frame, stamps={"d_rl": stamps})
    err = refused(capsys, path)
    assert "channel 'd_rl'" in err and "go back at sample 600" in err
    assert "one increasing clock per channel" in err


ERG_NAMES = {"Time": "t", "Car.vx": "vx", "Car.ax": "ax", "Car.ay": "ay", "Car.az": "az"}
ERG_NAMES |= {f"Susp.{w}": f"d_{w}" for w in WHEELS}


def write_erg_log(folder, rows: int | None = None):
    """The example log as a CarMaker ERG of doubles and its channel map."""
    frame = example_frame().iloc[:rows]
    columns = {name: frame[ours].to_numpy() for name, ours in ERG_NAMES.items()}
    path = folder / "run.erg"
    write_erg(path, columns, {"Time": "s"})
    channels = folder / "erg.toml"
    lines = ['[clock]\nchannel = "ax"']
    for name, ours in ERG_NAMES.items():
        if ours != "t":
            unit = "m" if ours.startswith("d_") else ("m/s" if ours == "vx" else "m/s^2")
            lines.append(f'[channels.{ours}]\nsource = "{name}"\nunit = "{unit}"')
    channels.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path, channels


def test_an_erg_log_is_estimated(tmp_path, capsys):
    path, channels = write_erg_log(tmp_path)
    code, out, err = estimate(capsys, path, "--channels", str(channels))
    assert code == 0 and err == "", err
    assert "1353 samples" in out


def test_an_erg_cut_on_a_record_boundary_is_refused(tmp_path, capsys):
    path, channels = write_erg_log(tmp_path)
    record = 8 * len(ERG_NAMES)
    path.write_bytes(path.read_bytes()[: 16 + 700 * record])  # 700 of 1353 whole records
    err = refused(capsys, path, "--channels", str(channels))
    assert f"{path}: has 700 records but its infofile declares File.NRecords = 1353" in err
    assert "copy the whole file again" in err


def test_an_erg_cut_inside_a_record_is_refused(tmp_path, capsys):
    path, channels = write_erg_log(tmp_path)
    path.write_bytes(path.read_bytes()[:-5])
    err = refused(capsys, path, "--channels", str(channels))
    assert "is not a whole number of 72-byte records" in err


def test_an_erg_with_a_bad_magic_is_refused(tmp_path, capsys):
    path, channels = write_erg_log(tmp_path)
    data = path.read_bytes()
    path.write_bytes(b"PK\x03\x04" + data[4:])  # e.g. a zip renamed .erg
    err = refused(capsys, path, "--channels", str(channels))
    assert f"{path}: does not start with 'CM-ERG'" in err and "not a CarMaker ERG" in err


def test_an_erg_without_a_declared_count_still_reads(tmp_path):
    """Files of other writers do not declare the count: read as they are."""
    path, _ = write_erg_log(tmp_path, rows=100)
    info = path.with_name(path.name + ".info")
    info.write_text(
        "\n".join(line for line in info.read_text().splitlines() if "NRecords" not in line)
    )
    channels = read_erg_channels(path, ["Car.ax"])
    assert channels["Car.ax"].values.shape == (100,)


def test_a_channel_map_that_is_not_utf8_is_named_as_the_map(tmp_path, capsys):
    log = tmp_path / "drive.csv"
    example_frame().to_csv(log, index=False)
    channels = tmp_path / "map.toml"
    channels.write_bytes(b'[time]\nsource = "t"\n# r\xe9glage\n')
    err = refused(capsys, log, "--channels", str(channels))
    assert f"{channels}: the channel map is not UTF-8 text" in err and "save it as UTF-8" in err
    assert "the log" not in err


def test_a_folder_given_as_channel_map_is_named_as_the_map(tmp_path, capsys):
    log = tmp_path / "drive.csv"
    example_frame().to_csv(log, index=False)
    folder = tmp_path / "maps"
    folder.mkdir()
    err = refused(capsys, log, "--channels", str(folder))
    assert f"{folder}: is a folder, not a channel map" in err


def test_quantised_travel_is_recognised_with_its_logger_step(tmp_path):
    """int16 travel in mm through a channel map: a 1 mm step per corner (to 1e-12 m, the
    rounding of converting the integers to metres); the float example log keeps its
    12-bit converter step, 150 mm / 4096 = 36.6 um."""
    frame = example_frame()
    for wheel in WHEELS:
        frame[f"d_{wheel}"] = (1000 * frame[f"d_{wheel}"]).round().astype("int16")
    path = tmp_path / "int16.parquet"
    frame.to_parquet(path, index=False)
    channels = tmp_path / "map.toml"
    lines = ['[time]\nsource = "t"']
    for name in ("ax", "ay", "az", "vx", *(f"d_{w}" for w in WHEELS)):
        unit = "mm" if name.startswith("d_") else ("m/s" if name == "vx" else "m/s^2")
        lines.append(f'[channels.{name}]\nsource = "{name}"\nunit = "{unit}"')
    channels.write_text("\n".join(lines) + "\n")
    signals = read_log(path, channels=channels)
    np.testing.assert_allclose(signals.travel_quantum, 1e-3, atol=1e-12)
    example = read_log(example_log_path())
    np.testing.assert_allclose(example.travel_quantum, 0.15 / 4096, rtol=1e-4)
    assert np.isnan(travel_quantum(np.full((5, 4), np.nan))).all()


def test_int16_travel_in_an_mf4_is_read_and_its_coarse_step_said(tmp_path, capsys):
    """An MF4 with travel as int16 mm (asammdf keeps the integer type) reads through a
    channel map; the 1 mm step is said in a line, the loads are finite."""
    frame = example_frame()[["t", "vx", "ax", "ay", "az", "d_fl", "d_fr", "d_rl", "d_rr"]]
    for wheel in WHEELS:
        frame[f"d_{wheel}"] = (1000 * frame[f"d_{wheel}"]).round().astype("int16")
    path = tmp_path / "int16.mf4"
    write_mf4(path, frame)
    channels = tmp_path / "map.toml"
    lines = []
    for name in ("ax", "ay", "az", "vx", *(f"d_{w}" for w in WHEELS)):
        unit = "mm" if name.startswith("d_") else ("m/s" if name == "vx" else "m/s^2")
        lines.append(f'[channels.{name}]\nsource = "{name}"\nunit = "{unit}"')
    channels.write_text("\n".join(lines) + "\n")
    out = tmp_path / "loads.csv"
    code, text, err = estimate(capsys, path, "--channels", str(channels), "--out", str(out))
    assert code == 0 and err == "", err
    assert "travel logged in steps of FL 1 mm FR 1 mm RL 1 mm RR 1 mm" in text
    assert np.isfinite(pd.read_csv(out)[[f"fz_{w}" for w in WHEELS]].to_numpy()).all()
