"""Log reading: round trips, errors naming file/column/row, unit checks, derived velocities."""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators import LogError, read_log, write_log
from wheelload.estimators.logs.signals import derive_velocities
from wheelload.studies.drive.synthetic import steady_cornering, synthetic_log


@pytest.fixture(scope="module")
def signals(vehicle):
    return synthetic_log(vehicle, steady_cornering(duration=3.0))


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_round_trip_keeps_every_channel(tmp_path, signals, suffix):
    path = tmp_path / f"log{suffix}"
    write_log(signals, path)
    back = read_log(path)
    np.testing.assert_allclose(back.d, signals.d, rtol=1e-12)
    np.testing.assert_allclose(back.v, signals.v, rtol=1e-12)
    np.testing.assert_allclose(back.reference, signals.reference, rtol=1e-12)
    assert not back.velocities_derived


def frame(signals):
    return signals.to_frame().drop(columns=[f"v_{w}" for w in ("fl", "fr", "rl", "rr")])


def write(tmp_path, data):
    path = tmp_path / "drive.csv"
    data.to_csv(path, index=False)
    return path


def test_missing_column_is_named(tmp_path, signals):
    path = write(tmp_path, frame(signals).drop(columns=["d_rl"]))
    with pytest.raises(LogError, match=r"drive\.csv: has column 'd_fl' but not 'd_rl'"):
        read_log(path)


def test_non_numeric_value_names_column_and_row(tmp_path, signals):
    data = frame(signals).astype({"ay": object})
    data.loc[7, "ay"] = "fast"
    with pytest.raises(LogError, match=r"column 'ay' is not numeric at row 7"):
        read_log(write(tmp_path, data))


def test_time_going_backwards_names_the_row(tmp_path, signals):
    data = frame(signals)
    data.loc[12, "t"] = data.loc[10, "t"]
    with pytest.raises(LogError, match=r"column 't' is not increasing at row 12"):
        read_log(write(tmp_path, data))


def test_acceleration_in_g_is_reported(tmp_path, signals):
    data = frame(signals)
    data["az"] /= 9.81
    with pytest.raises(LogError, match=r"column 'az'.*looks like g units"):
        read_log(write(tmp_path, data))


def test_travel_in_millimetres_is_reported(tmp_path, signals):
    data = frame(signals)
    data["d_fr"] *= 1000.0
    with pytest.raises(LogError, match=r"column 'd_fr'.*looks like mm"):
        read_log(write(tmp_path, data))


def test_partial_velocity_columns_are_rejected(tmp_path, signals):
    data = signals.to_frame().drop(columns=["v_rr"])
    with pytest.raises(LogError, match=r"'v_fl' but not 'v_rr'"):
        read_log(write(tmp_path, data))


def test_derived_velocity_matches_first_order_response():
    # 2 Hz sine at 1 kHz: the 20 Hz first-order differentiator has gain
    # 1/sqrt(1 + (f/fc)^2) = 0.995 and lag atan(f/fc) = 0.0997 rad; compare
    # the steady-state part with that analytic response to 0.5 % of the amplitude.
    t = np.arange(0.0, 3.0, 1e-3)
    omega = 2 * np.pi * 2.0
    d = 0.01 * np.sin(omega * t)[:, None] * np.ones(4)
    v = derive_velocities(t, d)
    ratio = 2.0 / 20.0
    expected = 0.01 * omega / np.sqrt(1 + ratio**2) * np.cos(omega * t - np.arctan(ratio))
    settled = t > 1.0
    np.testing.assert_allclose(v[settled, 0], expected[settled], atol=0.005 * 0.01 * omega)


def test_missing_travel_gives_missing_velocity_only_there():
    t = np.arange(0.0, 1.0, 0.01)
    d = np.tile(0.001 * t[:, None], (1, 4))
    d[30:33, 1] = np.nan
    v = derive_velocities(t, d)
    assert np.isnan(v[30:33, 1]).all()
    assert np.isfinite(np.delete(v[:, 1], [30, 31, 32])).all()
    assert np.isfinite(v[:, [0, 2, 3]]).all()


def test_unknown_extension_is_reported(tmp_path):
    path = tmp_path / "drive.xlsx"
    path.write_text("x")
    with pytest.raises(LogError, match="unknown log format"):
        read_log(path)


def test_user_data_is_not_altered(tmp_path, signals):
    data = frame(signals)
    data.loc[5, "d_fl"] = np.nan
    back = read_log(write(tmp_path, data))
    assert np.isnan(back.d[5, 0])
    np.testing.assert_allclose(back.d[6:, 0], data["d_fl"].to_numpy()[6:], rtol=1e-12)
    assert pd.isna(back.v[5, 0])


def test_signals_built_in_memory_are_shape_checked(signals):
    with pytest.raises(LogError, match=r"'d' has shape \(300, 3\), expected \(300, 4\)"):
        type(signals)(t=signals.t, vx=signals.vx, acc=signals.acc, d=signals.d[:, :3],
                      v=signals.v)  # fmt: skip


def test_signals_with_a_repeated_time_stamp_are_rejected(signals):
    t = signals.t.copy()
    t[11] = t[10]
    with pytest.raises(LogError, match=r"column 't' is not increasing at row 11"):
        type(signals)(t=t, vx=signals.vx, acc=signals.acc, d=signals.d, v=signals.v)


def test_derived_velocity_restarts_after_a_gap():
    # Travel moving at 0.02 m/s with a 0.5 s gap: holding the last value over the gap
    # would turn the jump into a false velocity of ~0.5 m/s; restarting at rest keeps
    # every derived velocity within the true rate (first-order response, no overshoot).
    t = np.arange(0.0, 3.0, 0.01)
    d = np.tile(0.02 * t[:, None], (1, 4))
    d[100:150, 0] = np.nan
    v = derive_velocities(t, d)
    assert np.all(np.abs(v[150:, 0]) <= 0.02 + 1e-12)
    assert np.isnan(v[100:150, 0]).all()


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda f: f.assign(ax=pd.to_datetime(f["t"], unit="s")), "column 'ax' has type"),
        (lambda f: f.assign(ay=pd.to_timedelta(f["t"], unit="s")), "column 'ay' has type"),
        (lambda f: f.assign(ay=f["ay"] > 0), "column 'ay' has type bool"),
        (lambda f: f.assign(t=(f["t"] * 1000).round()), "looks like milliseconds"),
    ],
    ids=["datetime", "timedelta", "bool", "milliseconds"],
)
def test_columns_of_the_wrong_kind_are_reported(tmp_path, signals, change, message):
    path = tmp_path / "drive.parquet"
    change(frame(signals)).to_parquet(path)
    with pytest.raises(LogError, match=message):
        read_log(path)
