"""The soft window's hoisted arithmetic (estimators/mhe/soft_window.py) against the
per-window functions it replaces: the Hessian values equal ``qp.hessian_values`` and the
windows refused as not finite are those ``qp.finite_data`` refuses. Tolerance: none (the
same operations on the same numbers)."""

import numpy as np

from wheelload.estimators.mhe.qp import finite_data, hessian_values, linear_term
from wheelload.estimators.mhe.soft_window import bad_windows, hessian_parts


def _rows(m: int, rng) -> dict:
    H = rng.standard_normal((m, 4, 4))
    return {
        "H": H + H.transpose(0, 2, 1),
        "g": rng.standard_normal((m, 4)),
        "link": rng.uniform(0.5, 2.0, m),
        "arrival": rng.standard_normal((m, 4, 4)),
        "xp": rng.standard_normal((m, 4)),
        "lower": np.full((m, 4), -np.inf),
        "upper": rng.uniform(1.0, 2.0, (m, 4)),
    }


def _not_finite(rows: dict, name: str) -> np.ndarray:
    values = rows[name]
    return ~np.isfinite(values.reshape(len(values), -1)).all(axis=1)


def _windows(rows: dict, N: int):
    for i in range(rows["link"].size - N):
        yield i, {name: values[i + 1 : i + 1 + N] for name, values in rows.items()}


def test_each_window_hessian_is_its_values_copied_from_the_samples():
    rng = np.random.default_rng(3)
    N, rows = 5, _rows(40, rng)
    inner, oldest, newest = hessian_parts(rows)
    for i, window in _windows(rows, N):
        a = i + 1
        Px = np.concatenate([oldest[a], inner[a + 1 : a + N - 1].ravel(), newest[a + N - 1]])
        assert np.array_equal(Px, hessian_values(window, 0, rng.standard_normal(4), False))


def test_the_windows_refused_are_those_finite_data_refuses():
    N, rows = 4, _rows(60, np.random.default_rng(5))
    rows["H"][10, 1, 2] = np.nan
    rows["g"][20, 3] = np.inf
    rows["link"][30] = np.inf  # in the windows after the one it is the oldest of
    rows["arrival"][40, 0, 0] = np.nan  # only in the window it is the oldest of
    rows["lower"][50, 0] = np.nan
    rows["upper"][55, 1] = -np.inf  # with lower's -inf: both infinities in no one array
    bad = bad_windows(
        _not_finite(rows, "H") | _not_finite(rows, "g"),
        _not_finite(rows, "link"),
        _not_finite(rows, "arrival"),
        (rows["lower"], rows["upper"]),
        N,
    )
    expected = []
    for _, window in _windows(rows, N):
        Px = hessian_values(window, 0, np.ones(4), False)
        q = linear_term(window, 0, np.ones(4), np.ones(4), False)
        expected.append(not finite_data(Px, q, window["lower"].ravel(), window["upper"].ravel()))
    assert bad.tolist() == expected
    assert 0 < bad.sum() < bad.size
