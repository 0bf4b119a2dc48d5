"""The file check's samples taken in one pass (ThinnedInputs) are every k-th sample, k the
largest power of two up to n // most: checked against that selection made on the whole
log at once, for chunkings that cut it anywhere. Tolerance: none (a selection)."""

import numpy as np
import pytest

from wheelload.estimators.kf.log_stream import ThinnedInputs
from wheelload.models import INPUTS


@pytest.mark.parametrize(
    ("n", "most", "rows"),
    [(10, 50, 3), (999, 50, 7), (1000, 50, 64), (12_345, 50, 1000), (50_000, 100, 4096)],
)
def test_one_pass_takes_every_power_of_two_th_sample(n, most, rows):
    rng = np.random.default_rng(n)
    t = np.cumsum(rng.uniform(0.005, 0.015, n))
    columns = {name: rng.standard_normal(n) for name in INPUTS if name != "az"}
    columns["az"] = np.broadcast_to(9.8, (n,))  # an assumed channel, broadcast as read
    thinned = ThinnedInputs(most)
    for start in range(0, n, rows):
        part = {name: values[start : start + rows] for name, values in columns.items()}
        thinned.add(t[start : start + rows], part)
    step = 1
    while 2 * step <= max(1, n // most):
        step *= 2
    keep = np.arange(0, n, step)
    times, inputs = thinned.result()
    assert np.array_equal(times, t[keep])
    expected = np.vstack([np.broadcast_to(columns[name], (n,))[keep] for name in INPUTS])
    assert np.array_equal(inputs, expected)
    assert keep.size <= max(n, 4 * most)
