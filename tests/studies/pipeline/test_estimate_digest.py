"""The digest's error figures, computed in place in its store, equal the plain computation.

Tolerance zero for RMSE (per wheel), P95 and Max: the same operations on the same
numbers in the same order; the pooled RMSE sums per wheel (1e-15 relative).
"""

import os

import numpy as np
import pytest

from wheelload.studies.pipeline import error_store
from wheelload.studies.pipeline.error_store import linear_percentile, order_statistic
from wheelload.studies.pipeline.estimate_digest import EstimateDigest


def _plain(errors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """RMSE, P95 and Max of |errors| per wheel (columns), on copies."""
    absolute = np.abs(errors)
    rmse = np.array([np.sqrt(np.mean(absolute[:, i] * absolute[:, i])) for i in range(4)])
    p95 = np.array([np.percentile(absolute[:, i], 95) for i in range(4)])
    return rmse, p95, absolute.max(axis=0)


@pytest.mark.parametrize("store", ["memory", "disk", "growing", "growing to disk"])
def test_the_figures_equal_the_plain_ones_in_chunks_with_gaps(store, monkeypatch, tmp_path):
    """In memory and on disk (the store's files in a private folder under TMPDIR, removed
    once the figures are made); a log's length not known (the one read of the lean path):
    grown in memory, or grown and then, beyond the memory limit, moved to disk."""
    if store == "disk":
        monkeypatch.setattr(error_store, "MEMORY_LIMIT", 0)
    if store.startswith("growing"):
        monkeypatch.setattr(error_store, "FIRST_ROWS", 5000)  # 5000 -> 10000 -> 20000 rows
    if store == "growing to disk":
        monkeypatch.setattr(error_store, "MEMORY_LIMIT", 8 * 4 * 8000)  # 10000 rows: disk
    monkeypatch.setattr(error_store.tempfile, "tempdir", str(tmp_path))
    rng = np.random.default_rng(7)
    n = 20_000
    reference = 4000.0 + 500.0 * rng.standard_normal((n, 4))
    errors = 40.0 * rng.standard_normal((n, 4))
    errors[:, 3] *= 1e-160  # errors whose squares leave the normal range: the other route
    errors[::97, 2] = 0.0
    reference[5::301, 1] = np.nan  # unscored samples: the store has a tail
    loads = reference + errors
    known = None if store.startswith("growing") else n
    digest = EstimateDigest(samples=known, reference_wheels=np.ones(4, bool))
    if store == "growing to disk":
        assert not digest.errors.on_disk  # in memory at first
    for start in range(0, n, 6000):
        part = slice(start, start + 6000)
        m = len(loads[part])
        digest.add(loads[part], np.ones((m, 4)), np.zeros(m, np.uint32), reference[part])
    assert digest.errors.on_disk == (store in ("disk", "growing to disk"))
    names, rows = digest.metric_rows("log.csv")
    scored = np.all(np.isfinite(reference), axis=1)
    expected = (loads - reference)[scored]
    rmse, p95, peak = _plain(expected)
    table = np.array(rows)
    assert names == ["fl", "fr", "rl", "rr", "pooled"]
    assert np.array_equal(table[:4, 0], rmse)
    assert np.array_equal(table[:4, 2], p95)
    assert np.array_equal(table[:4, 3], peak)
    pooled = np.abs(expected).reshape(-1)
    assert table[4, 2] == np.percentile(pooled, 95)
    assert np.isclose(table[4, 0], np.sqrt(np.mean(pooled * pooled)), rtol=1e-15, atol=0)
    assert os.listdir(tmp_path) == []  # the disk store's folder is gone


@pytest.mark.parametrize("n", [1, 2, 3, 20, 21, 101, 1000, 4097, 99_999])
def test_the_pooled_percentile_by_selection_is_numpys(n):
    """Order statistics by bisection on bit patterns over sorted columns, then NumPy's
    interpolation: equal to ``np.percentile`` to the bit (ties, zeros and sizes whose
    virtual index falls on, below and above .5)."""
    rng = np.random.default_rng(n)
    values = np.abs(rng.standard_normal(n) * 50.0)
    values[::7] = np.round(values[::7])  # ties
    values[::11] = 0.0
    columns = [np.sort(part) for part in np.array_split(values, 4)]
    for q in (0.0, 50.0, 95.0, 99.9, 100.0):
        expected = np.percentile(values, q)
        got = linear_percentile(n, q, lambda k: order_statistic(columns, k))
        assert got == expected, (q, got, expected)
