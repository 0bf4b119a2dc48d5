"""A drive log read chunk by chunk gives the data set of the whole-table reader, to the bit.

The chunked read (the default for CSV and Parquet logs named as ours) derives
the travel rates and body-rate derivatives chunk by chunk with the filters'
state carried. The bundled plant log tiled 49 times (66 297 rows, time kept
increasing) is longer than the reader's chunk of 65 536 rows, so each variant
crosses a chunk boundary inside the filters' runs. Variants: as tiled (CSV and
Parquet), and as Parquet without the travel rates (derived), without the body
rates (optional channels absent), with irregular time stamps (no body-rate
derivatives: absent), with wheel speeds for ``vx``, with gaps.
"""

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.identification import default_model, read_drive
from wheelload.models.runtime.spill import on_disk
from wheelload.studies.pipeline.example_log import example_log_path

TILES = 49


def _tiled() -> pd.DataFrame:
    lap = pd.read_csv(example_log_path(), comment="#")
    span = lap["t"].iloc[-1] - lap["t"].iloc[0] + float(np.median(np.diff(lap["t"])))
    return pd.concat([lap.assign(t=lap["t"] + k * span) for k in range(TILES)], ignore_index=True)


def _variant(name: str, frame: pd.DataFrame) -> pd.DataFrame:
    frame = frame.copy()
    if name == "no-rates":
        return frame.drop(columns=["wx", "wy", "wz"])
    if name == "no-travel-rates":
        return frame.drop(columns=["v_fl", "v_fr", "v_rl", "v_rr"])
    if name == "irregular-time":
        frame["t"] += np.where(np.arange(len(frame)) % 7 == 0, 0.004, 0.0)
        return frame
    if name == "wheel-speeds":
        frame["ws_fl"], frame["ws_fr"] = frame["vx"], 1.01 * frame["vx"]
        return frame.drop(columns=["vx"])
    if name == "gaps":
        frame.loc[100:120, "d_fl"] = np.nan
        frame.loc[300, "fz_fr"] = np.nan
        frame.loc[500:510, "wx"] = np.nan
    return frame


@pytest.mark.parametrize(
    ("variant", "absent"),
    [
        ("csv", set()),
        ("parquet", set()),
        ("no-rates", {"wx", "wy", "wz", "wx_dot", "wy_dot", "wz_dot"}),
        ("no-travel-rates", set()),
        ("irregular-time", {"wx_dot", "wy_dot", "wz_dot"}),
        ("wheel-speeds", set()),
        ("gaps", set()),
    ],
)
def test_chunked_read_equals_the_whole_table(tmp_path, variant, absent):
    model = default_model()
    frame = _variant(variant, _tiled())
    if variant == "csv":
        path = tmp_path / "tiled.csv"
        frame.to_csv(path, index=False)
    else:
        path = tmp_path / f"{variant}.parquet"
        frame.to_parquet(path, index=False)
    chunked = read_drive(path, model.channel_names(), model.optional)
    whole = read_drive(path, model.channel_names(), model.optional, in_memory=True)
    assert chunked.absent == whole.absent == frozenset(absent)
    assert list(chunked.signals) == list(whole.signals) == list(model.channel_names())
    np.testing.assert_array_equal(chunked.t, whole.t)
    np.testing.assert_array_equal(chunked.target, whole.target)
    for name, values in whole.signals.items():
        np.testing.assert_array_equal(chunked.signals[name], values, err_msg=name)
    assert len(whole) > 1 << 16 and np.isfinite(chunked.target).sum() > 1 << 18


@pytest.mark.parametrize(("variant", "absent"), [("gaps", set()), ("no-rates", {"wx", "wy"})])
def test_a_data_set_kept_on_disk_equals_the_one_in_memory(tmp_path, variant, absent):
    """``spill_bytes=0``: every column on a temporary file, mapped (the path a long log
    takes); the same numbers, the absent channels zeros that take no memory."""
    model = default_model()
    path = tmp_path / f"{variant}.parquet"
    _variant(variant, _tiled()).to_parquet(path, index=False)
    spilled = read_drive(path, model.channel_names(), model.optional, spill_bytes=0)
    whole = read_drive(path, model.channel_names(), model.optional, in_memory=True)
    assert on_disk(spilled.t) and on_disk(spilled.target)
    np.testing.assert_array_equal(spilled.t, whole.t)
    np.testing.assert_array_equal(spilled.target, whole.target)
    for name, values in whole.signals.items():
        assert on_disk(spilled.signals[name]) != (name in spilled.absent), name
        np.testing.assert_array_equal(spilled.signals[name], values, err_msg=name)
    assert absent <= spilled.absent
