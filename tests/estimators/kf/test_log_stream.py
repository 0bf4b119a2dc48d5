"""The lean whole-log path equals the in-memory one: numbers to the bit, files, summaries.

Tolerance: none for the estimates (the same generated C arithmetic on the same
inputs, chunked or not: bit-identical); the summary's means are sums in
another order, 1e-12 relative.
"""

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from wheelload.estimators import read_log
from wheelload.estimators.kf.log_stream import scan_log
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.estimators.logs.output_files import OutputError, table_writer
from wheelload.estimators.logs.signals import Differentiator, derive_velocities
from wheelload.estimators.types import Steps
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.pipeline.estimate_digest import EstimateDigest
from wheelload.studies.pipeline.example_log import example_log_path
from wheelload.studies.pipeline.summary import digest_of

VEHICLE = str(example_vehicle_path())
ROWS = 37  # a prime: chunk boundaries fall inside gaps, faults and runs


@pytest.fixture(scope="module")
def example():
    return pd.read_csv(example_log_path())


@pytest.fixture(scope="module")
def kf(vehicle):
    """The filter the streamed path runs: sample by sample, no whole-log file check."""
    return TwoStageKF(vehicle, check_file=False)


def _variants(example):
    derived = example.drop(columns=["v_fl", "v_fr", "v_rl", "v_rr"])
    derived.loc[30:80, "d_fl"] = np.nan  # a gap across chunk boundaries
    derived.loc[111, "d_rr"] = np.nan  # a one-sample gap at a boundary (111 = 3 * 37)
    derived.loc[300:302, "ax"] = np.inf
    wheels = example.drop(columns=["vx", "az"]).assign(
        ws_fl=example["vx"], ws_fr=example["vx"] + 0.1, ws_rl=np.nan, ws_rr=example["vx"]
    )
    travel_fault = example.copy()
    travel_fault.loc[400:700, "d_fl"] += 0.03  # isolated as a d_fl fault from 4.65 s
    imu = example.drop(columns=["d_fl", "d_fr", "d_rl", "d_rr", "v_fl", "v_fr", "v_rl", "v_rr"])
    return {"example": example, "derived": derived, "wheel_speeds": wheels,
            "travel_fault": travel_fault, "imu_only": imu}  # fmt: skip


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
@pytest.mark.parametrize(
    "variant", ["example", "derived", "wheel_speeds", "travel_fault", "imu_only"]
)
def test_the_lean_path_equals_run_to_the_bit(tmp_path, example, kf, suffix, variant):
    frame = _variants(example)[variant]
    path = tmp_path / f"log{suffix}"
    frame.to_csv(path, index=False) if suffix == ".csv" else frame.to_parquet(path)
    signals = read_log(path, wiring_checks=False)
    expected = kf.run(signals)
    stream = scan_log(path, rows=ROWS, wiring_checks=False)
    faults = []
    chunks = list(stream.chunks(kf, faults=faults))
    assert len(chunks) == -(-len(frame) // ROWS)
    for name in ("loads", "std", "residual"):
        got = np.concatenate([getattr(c, name) for c in chunks])
        assert np.array_equal(got, getattr(expected, name)), name
    flags = np.concatenate([c.flags for c in chunks])
    assert flags.dtype == np.uint32 and np.array_equal(flags, expected.flags)
    assert faults == list(expected.sensor_faults)
    if variant == "travel_fault":
        assert [f.channel for f in faults] == ["d_fl"]
    assert stream.mode() == signals.mode()
    assert stream.velocities_derived == signals.velocities_derived
    assert np.array_equal(stream.t, signals.t)


def test_the_differentiator_in_chunks_equals_one_call(example):
    t = example["t"].to_numpy()
    d = example[["d_fl", "d_fr", "d_rl", "d_rr"]].to_numpy().copy()
    d[37:90, 0] = np.nan
    d[73, 1] = np.nan
    d[-5:, 2] = np.nan
    whole = derive_velocities(t, d)
    differentiator = Differentiator(Steps.of(t), 4)
    parts = [differentiator(d[k : k + 37]) for k in range(0, len(d), 37)]
    assert np.array_equal(np.concatenate(parts), whole, equal_nan=True)


def test_the_digest_in_chunks_equals_the_whole_log(example, kf):
    signals = read_log(example_log_path(), wiring_checks=False)
    estimate = kf.run(signals)
    whole = digest_of(estimate, signals)
    chunked = EstimateDigest(samples=len(estimate), reference_wheels=np.ones(4, bool))
    for k in range(0, len(estimate), ROWS):
        rows = slice(k, k + ROWS)
        chunked.add(estimate.loads[rows], estimate.std[rows], estimate.flags[rows],
                    signals.reference[rows])  # fmt: skip
    np.testing.assert_allclose(chunked.means(), whole.means(), rtol=1e-12)
    np.testing.assert_allclose(chunked.mean_std(), whole.mean_std(), rtol=1e-12)
    assert np.array_equal(chunked.load_min, whole.load_min)
    a, b = chunked.metrics("log"), whole.metrics("log")
    assert np.array_equal(a[["RMSE", "P95", "Max"]], b[["RMSE", "P95", "Max"]])
    np.testing.assert_allclose(a["RMSE %"], b["RMSE %"], rtol=1e-12)


def _estimate(*argv):
    return main(["estimate", *map(str, argv), "--vehicle", VEHICLE])


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_estimate_writes_the_same_file_and_summary_on_both_paths(tmp_path, capsys, suffix):
    lean, whole = tmp_path / f"lean{suffix}", tmp_path / f"whole{suffix}"
    assert _estimate(example_log_path(), "--out", lean) == 0
    lean_text = capsys.readouterr().out
    assert _estimate(example_log_path(), "--out", whole, "--in-memory") == 0
    assert capsys.readouterr().out.replace(str(whole), str(lean)) == lean_text
    if suffix == ".csv":
        assert lean.read_bytes() == whole.read_bytes()
        frame = pd.read_csv(lean)
    else:
        assert pq.read_schema(lean).field("status").type == "uint32"
        frame = pd.read_parquet(lean)
    kf = TwoStageKF(read_vehicle())
    expected = kf.run(read_log(example_log_path())).to_pandas()
    assert list(frame.columns) == list(expected.columns)
    for column in expected.columns:  # the round trip gives back the same doubles
        assert np.array_equal(frame[column].to_numpy(), expected[column].to_numpy()), column


def read_vehicle():
    from wheelload.models import load_vehicle

    return load_vehicle(example_vehicle_path())


def test_still_period_and_corner_weights_on_both_paths(tmp_path, capsys, example):
    rest = pd.DataFrame([example.iloc[0]] * 200).reset_index(drop=True)
    rest[["vx", "ax", "ay", "wx", "wy", "wz", "v_fl", "v_fr", "v_rl", "v_rr"]] = 0.0
    rest["az"] = 9.81
    moving = example.copy()
    frame = pd.concat([rest, moving], ignore_index=True)
    frame["t"] = np.arange(len(frame)) * 0.01
    log = tmp_path / "rest.parquet"
    frame.to_parquet(log)
    options = ["--still-period", "1.5", "--corner-weights", "440,440,370,370"]
    lean, whole = tmp_path / "lean.csv", tmp_path / "whole.csv"
    assert _estimate(log, "--out", lean, *options) == 0
    lean_text = capsys.readouterr().out
    assert _estimate(log, "--out", whole, "--in-memory", *options) == 0
    assert capsys.readouterr().out.replace(str(whole), str(lean)) == lean_text
    assert "still period 0-1.5 s" in lean_text
    assert lean.read_bytes() == whole.read_bytes()


def test_the_output_rules_hold_on_the_lean_path(tmp_path, capsys):
    log = tmp_path / "drive.csv"
    log.write_bytes(example_log_path().read_bytes())
    out = tmp_path / "loads.csv"
    out.write_text("keep me")
    assert _estimate(log, "--out", out) == 2
    assert "exists" in capsys.readouterr().err and out.read_text() == "keep me"
    assert _estimate(log, "--out", log, "--force") == 2
    assert "is the input file" in capsys.readouterr().err
    assert _estimate(log, "--out", out, "--force") == 0
    assert pd.read_csv(out).shape[0] == pd.read_csv(log).shape[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drive.csv", "loads.csv"]


def test_an_interrupted_table_leaves_nothing(tmp_path):
    out = tmp_path / "loads.parquet"
    with pytest.raises(RuntimeError, match="stop"):
        with table_writer(out) as write:
            write({"t": np.arange(3.0), "status": np.zeros(3, np.uint32)})
            raise RuntimeError("stop")
    assert list(tmp_path.iterdir()) == []
    out.write_text("old")
    with pytest.raises(OutputError, match="appeared while writing"):
        with table_writer(out) as write:
            write({"t": np.arange(3.0)})
    assert out.read_text() == "old" and len(list(tmp_path.iterdir())) == 1


def test_a_log_with_comments_goes_the_ordinary_way(tmp_path, capsys, example):
    plain, commented = tmp_path / "plain.csv", tmp_path / "commented.csv"
    example.to_csv(plain, index=False)
    text = plain.read_text().splitlines()
    commented.write_text("\n".join(["# logger v2", *text[:50], "# lap 1", *text[50:]]) + "\n")
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert _estimate(plain, "--out", a) == 0
    assert _estimate(commented, "--out", b) == 0
    assert a.read_bytes() == b.read_bytes()


def test_a_bad_value_is_named_as_on_the_ordinary_path(tmp_path, capsys, example):
    frame = example.astype(object)
    frame.loc[17, "ax"] = "n/a?"
    log = tmp_path / "bad.csv"
    frame.to_csv(log, index=False)
    assert _estimate(log) == 2
    assert "column 'ax' is not numeric at row 17" in capsys.readouterr().err


def test_rate_derivatives_derived_where_no_load_term_reads_them(tmp_path, example, vehicle):
    """Body inertia and the IMU lever arm off: the lean path still estimates the rate
    derivatives (rates logged, no wx_dot), since the fault monitor's parity test uses every
    term the inputs allow, and equals run to the bit (a +1 m/s^2 ay bias on a paper-model
    lap was isolated 2.7 s later on the lean path when it skipped them)."""
    import dataclasses

    off = dataclasses.replace(
        vehicle, model=dataclasses.replace(vehicle.model, body_inertia=False, imu_lever_arm=False)
    )
    kf_off = TwoStageKF(off)
    path = tmp_path / "log.csv"
    example.to_csv(path, index=False)
    expected = kf_off.run(read_log(path, wiring_checks=False))
    chunks = list(scan_log(path, rows=ROWS, wiring_checks=False).chunks(kf_off))
    for name in ("loads", "std", "residual"):
        got = np.concatenate([getattr(c, name) for c in chunks])
        assert np.array_equal(got, getattr(expected, name)), name
    assert np.array_equal(np.concatenate([c.flags for c in chunks]), expected.flags)


def test_arrow_columns_read_as_to_numpy_reads_them():
    """The chunk reader's arrow-to-numpy (no pandas import) equals ``to_numpy``: values,
    NaN for nulls, sliced arrays, and a read-only view where there is no null."""
    import pyarrow as pa

    from wheelload.estimators.logs.readers.chunks import float_values

    with_nulls = pa.array([1.0, None, 3.0, 4.0, None, 6.0, 7.0, 8.0, 9.0, None, 11.0])
    plain = pa.array(np.arange(20.0))
    for array in (with_nulls, with_nulls.slice(1, 7), with_nulls.slice(9, 2),
                  with_nulls.slice(5, 3), plain, plain.slice(5, 7), plain.slice(0, 0),
                  pa.nulls(5, pa.float64())):  # fmt: skip
        got, expected = float_values(array), array.to_numpy(zero_copy_only=False)
        assert got.dtype == np.float64
        assert np.array_equal(got, expected, equal_nan=True)
        assert got.flags.writeable == expected.flags.writeable


@pytest.mark.parametrize("wrong", ["no bars", "travel zero"])
def test_the_streamed_file_check_equals_run(tmp_path, example, vehicle, wrong):
    """A file without anti-roll bars, or d_fl 3 mm off its zero: the streamed path's file
    check (every sample of this short log, read in chunks) names what ``TwoStageKF.run``
    names and gives its loads and widened σ to the bit."""
    import dataclasses

    from wheelload.estimators.logs.model_error import MAX_SAMPLES, diagnose_inputs

    frame = example.copy()
    if wrong == "travel zero":
        frame["d_fl"] += 0.003
    else:
        axles = {
            axle: dataclasses.replace(getattr(vehicle.suspension, axle), arb_rate=0.0)
            for axle in ("front", "rear")
        }
        vehicle = vehicle.replace(suspension=dataclasses.replace(vehicle.suspension, **axles))
    path = tmp_path / "log.csv"
    frame.to_csv(path, index=False)
    whole = TwoStageKF(vehicle).run(read_log(path, wiring_checks=False))
    stream = scan_log(path, rows=ROWS, wiring_checks=False)
    _, inputs = stream.thinned_inputs(MAX_SAMPLES).result()
    lean = TwoStageKF(vehicle, check_file=False)
    properties = lean.run(read_log(path, wiring_checks=False)).mass_properties[-1]
    diagnosis = diagnose_inputs(inputs, vehicle, mass_properties=properties)
    assert (diagnosis.finding,) == whole.model_errors
    chunks = list(stream.chunks(lean, diagnosis=diagnosis))
    for name in ("loads", "std"):
        got = np.concatenate([getattr(c, name) for c in chunks])
        assert np.array_equal(got, getattr(whole, name)), name
