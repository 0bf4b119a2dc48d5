"""Study cache entries are data only and give back the stored values to the bit."""

import json
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest

from wheelload.studies.experiments.runs.cache_entries import (
    CacheEntryError,
    read_entry,
    write_entry,
)
from wheelload.studies.experiments.runs.units import TrialResult


def _metrics(rng) -> pd.DataFrame:
    return pd.DataFrame(rng.standard_normal((5, 4)), index=["fl", "fr", "rl", "rr", "pooled"],
                        columns=["RMSE", "RMSE %", "P95", "Max"])  # fmt: skip


def test_a_trial_result_and_a_frame_come_back_to_the_bit(tmp_path):
    rng = np.random.default_rng(3)
    result = TrialResult(
        metrics={"kf": _metrics(rng), "mhe": _metrics(rng)},
        errors={"D": "ValueError: no travel"},
        seconds_per_sample={"kf": 1.25e-6},
        t=np.arange(5.0),
        s=rng.standard_normal(5),
        reference=rng.standard_normal((5, 4)),
        estimates={"kf": rng.standard_normal((5, 4)).astype(np.float32)},
    )
    frame = pd.DataFrame({"t": rng.standard_normal(7), "flag": np.arange(7) % 2 == 0,
                          "name": list("abcdefg")})  # fmt: skip
    value = [result, (frame, None, 3, "x", float("nan"))]
    write_entry(tmp_path / "e.npz", "k", value)
    back = read_entry(tmp_path / "e.npz", "k")
    got, (got_frame, none, three, x, nan) = back[0], back[1]
    assert (none, three, x) == (None, 3, "x") and np.isnan(nan)
    pd.testing.assert_frame_equal(got_frame, frame, check_exact=True)
    for name in ("kf", "mhe"):
        pd.testing.assert_frame_equal(got.metrics[name], result.metrics[name], check_exact=True)
    assert got.errors == result.errors and got.seconds_per_sample == result.seconds_per_sample
    for field in ("t", "s", "reference"):
        np.testing.assert_array_equal(getattr(got, field), getattr(result, field))
    assert got.estimates["kf"].dtype == np.float32
    np.testing.assert_array_equal(got.estimates["kf"], result.estimates["kf"])


def test_what_is_not_data_is_refused_when_stored_and_when_read(tmp_path):
    @dataclass(frozen=True)
    class Other:
        x: int

    with pytest.raises(TypeError, match="cannot hold a Other"):
        write_entry(tmp_path / "a.npz", "k", Other(x=1))
    with pytest.raises(TypeError, match="object arrays of strings only"):
        write_entry(tmp_path / "b.npz", "k", np.array([object()], dtype=object))
    # a manifest naming a type outside VALUE_TYPES: never imported
    manifest = {"format": "wheelload-cache-1", "key": "k",
                "value": {"dataclass": "os:system", "fields": {}}}  # fmt: skip
    text = json.dumps(manifest).encode()
    with (tmp_path / "c.npz").open("wb") as stream:
        np.savez(stream, manifest=np.frombuffer(text, np.uint8))
    with pytest.raises(CacheEntryError, match="os:system is not one a cache entry holds"):
        read_entry(tmp_path / "c.npz", "k")
