"""Median and percentile without numpy.ma (estimators/kernels/order_statistics.py): numpy's
numbers to the bit, on random data with repeats, NaNs, odd and even counts."""

import numpy as np
import pytest

from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.kernels.order_statistics import median, nanmedian, percentile


def _samples(seed: int, count: int = 400):
    rng = np.random.default_rng(seed)
    for trial in range(count):
        n = int(rng.integers(1, 40)) if trial % 3 else int(rng.integers(40, 3000))
        x = rng.normal(size=n) * 10 ** rng.uniform(-3, 5)
        if trial % 4 == 1:
            x = np.round(x, 2)  # ties
        if trial % 4 == 2:
            x[rng.random(n) < 0.1] = np.nan
        yield rng, x


def _same(a, b) -> bool:
    """Equal to the bit (NaN equal to NaN)."""
    return np.array_equal(np.float64(a), np.float64(b), equal_nan=True)


def test_median_is_numpys():
    for _, x in _samples(1):
        assert _same(median(x), np.median(x)), x.size
        mine = x.copy()
        assert _same(median(mine, overwrite_input=True), np.median(x)), x.size


def test_median_along_the_last_axis_is_numpys():
    for rng, x in _samples(2, 100):
        windows = np.column_stack([x, rng.permutation(x), np.roll(x, 1)])
        assert np.array_equal(median(windows, axis=-1), np.median(windows, axis=1), equal_nan=True)
        assert np.array_equal(median(windows.T.copy(), axis=1), np.median(windows.T, axis=1),
                              equal_nan=True)  # fmt: skip


def test_nanmedian_is_numpys():
    for rng, x in _samples(3):
        y = x.copy()
        y[rng.random(y.size) < 0.2] = np.nan
        if np.isnan(y).all():
            continue
        assert _same(nanmedian(y), np.nanmedian(y))
        mine = y.copy()
        assert _same(nanmedian(mine, overwrite_input=True), np.nanmedian(y))


@pytest.mark.parametrize("q", [0.0, 5.0, 50.0, 95.0, 99.0, 100.0, 37.3])
def test_percentile_is_numpys(q):
    for _, x in _samples(4, 200):
        assert _same(percentile(x, q), np.percentile(x, q)), (x.size, q)
        mine, theirs = x.copy(), x.copy()
        assert _same(percentile(mine, q, overwrite_input=True),
                     np.percentile(theirs, q, overwrite_input=True))  # fmt: skip


def test_a_median_along_another_axis_or_a_percentile_out_of_range_is_refused():
    with pytest.raises(ValueError, match="last axis"):
        median(np.zeros((3, 4)), axis=0)
    with pytest.raises(ValueError, match="range"):
        percentile(np.zeros(3), 101.0)


def _passes(values: np.ndarray, block: int):
    """A pass over ``values`` in blocks of ``block``, counting the passes made."""
    made = []

    def blocks():
        made.append(1)
        for start in range(0, values.size, block):
            yield values[start : start + block]

    return blocks, made


@pytest.mark.parametrize(
    "kind", ["normal", "heavy-tailed", "ties", "one-value", "clustered", "tiny-spread"]
)
@pytest.mark.parametrize("n", [40_001, 40_000])
def test_blocked_median_is_numpys_with_a_small_gather(kind, n):
    """Selection over passes, with at most 500 values gathered (80 times fewer than the
    data), gives numpy's median exactly, also with ties, one repeated value, a cluster
    far from the rest and a spread of a few ulps."""
    rng = np.random.default_rng(7)
    values = {
        "normal": rng.normal(3.0, 2.0, n),
        "heavy-tailed": rng.standard_cauchy(n),
        "ties": rng.integers(-5, 6, n).astype(float),
        "one-value": np.full(n, -2.5),
        "clustered": np.concatenate([rng.normal(0, 1e-9, n - 7), rng.normal(1e6, 1, 7)]),
        "tiny-spread": 1.0 + rng.integers(0, 4, n) * np.finfo(float).eps,
    }[kind]
    blocks, made = _passes(values, 3_333)
    assert order_statistics.blocked_median(blocks, n, gather=500) == np.median(values)
    assert len(made) <= 24  # each selection: a few count, bin and gather passes


def test_blocked_kth_is_the_sorted_value_at_every_rank():
    rng = np.random.default_rng(3)
    values = rng.normal(0, 1, 5_000) ** 3
    ordered = np.sort(values)
    blocks, _ = _passes(values, 701)
    for k in (0, 1, 2_499, 2_500, 4_998, 4_999):
        assert order_statistics.blocked_kth(blocks, values.size, k, gather=64) == ordered[k]
