r"""The soft window (four loads per sample) over a log, its arithmetic hoisted out of the loop.

:func:`~wheelload.estimators.mhe.ring.run_ring` hands the plain soft window
here (quadratic losses, no bias states, :math:`N > 1`), as it hands the hard one to
:func:`~wheelload.estimators.mhe.ring.run_hard`. Every per-sample term is known
before the loop (each field one array over the initial window and the log,
``rows``: name -> ``(N + n, ...)``; the window of sample ``i`` is
``[i + 1 : i + 1 + N]``), so the block-tridiagonal Hessian's values
(:func:`~wheelload.estimators.mhe.qp.hessian_values`) are formed once per sample,
in OSQP's CSC order (:func:`~wheelload.estimators.mhe.qp.csc_value_order`):

- an interior sample :math:`j`: its coupling :math:`-\ell_j I` to the sample
  before, interleaved with :math:`H_j + (\ell_j + \ell_{j+1}) I` (14 values);
- the window's oldest sample :math:`a`: :math:`(H_a + \ell_{a+1} I) + \Pi_a^{-1}`,
  the arrival weight on it (10 values);
- the newest: its coupling and :math:`H_j + \ell_j I` (14 values).

A window's ``Px`` is then one copy of its interior samples' values plus its
two end blocks, and ``q`` one copy of the samples' terms :math:`g_j` less the
arrival prior's :math:`\Pi_a^{-1} \bar x / s` on the oldest. Which windows hold
a value that is not finite (:func:`~wheelload.estimators.mhe.qp.finite_data`,
entry by entry) and which samples' loads cannot be told from a held estimate
are counted once over the log too. The numbers and the OSQP calls are those of
the per-sample state path (:meth:`MovingHorizonEstimator.step`), bit for bit
(tested); the first :math:`N - 1` samples of a log, whose windows start with
inert samples (:math:`j_0 > 0`), take :func:`~wheelload.estimators.mhe.qp.hessian_values`
and :func:`~wheelload.estimators.mhe.qp.linear_term` themselves.

Example
-------
>>> loads, status, iterations, fallback, solve_time, final = run_soft(mhe, state, rows, kf)
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.mhe.qp import (
    finite_data,
    hessian_values,
    linear_term,
)
from wheelload.estimators.mhe.terms import LOAD_SCALE
from wheelload.estimators.mhe.window_loop import run_window

#: A 4 x 4 block's upper triangle in CSC order: (row, column) by column, then row.
_UPPER = tuple(zip(*[(r, a) for a in range(4) for r in range(a + 1)], strict=True))
#: Where an interior sample's couplings sit among its 14 values (one before each column).
_COUPLING = np.array([0, 2, 5, 9])
_BLOCK = np.setdiff1d(np.arange(14), _COUPLING)


def _upper(blocks: np.ndarray) -> np.ndarray:
    """(m, 4, 4) -> (m, 10): each block's upper triangle in CSC order."""
    return blocks[:, _UPPER[0], _UPPER[1]]


def _window_counts(bad: np.ndarray, N: int) -> np.ndarray:
    """Per window ``[i + 1, i + 1 + N)`` of ``bad`` (length N + n): how many are true."""
    total = np.concatenate([[0], np.cumsum(bad, dtype=np.int64)])
    return total[1 + N :] - total[1:-N]


def hessian_parts(rows: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each sample's values inside a window (14), as its oldest (10) and as its newest (14).

    The arithmetic of :func:`~wheelload.estimators.mhe.qp.hessian_values` for a window
    whose arrival weight is on its oldest sample: its ``diagonal`` is
    :math:`0 + \\ell_{a+1}` on the oldest, :math:`\\ell_j + \\ell_{j+1}` inside,
    :math:`\\ell_j` on the newest, added as ``diagonal * I``.
    """
    H, L, W = rows["H"], rows["link"], rows["arrival"]
    m = L.size
    eye = np.eye(4)
    inner = np.zeros((m, 14))
    inner[:, _COUPLING] = -L[:, None]
    inner[:-1, _BLOCK] = _upper(H[:-1] + (L[:-1] + L[1:])[:, None, None] * eye)
    oldest = np.zeros((m, 10))
    first = H[:-1] + (0.0 + L[1:])[:, None, None] * eye
    first += W[:-1]
    oldest[:-1] = _upper(first)
    newest = inner.copy()
    newest[:, _BLOCK] = _upper(H + L[:, None, None] * eye)
    return inner, oldest, newest


def _not_finite(values: np.ndarray) -> np.ndarray:
    """Per sample (first axis): whether any of its values is not finite."""
    return ~np.isfinite(values.reshape(values.shape[0], -1)).all(axis=1)


def bad_windows(
    every: np.ndarray, after_oldest: np.ndarray, oldest: np.ndarray, bounds, N: int
) -> np.ndarray:
    """Windows (arrival weight on the oldest sample) that
    :func:`~wheelload.estimators.mhe.qp.finite_data` refuses, entry by entry.

    A window ``[a, a + N)`` (``a = i + 1``) is refused when a sample's flag in
    ``every`` is set, one after its oldest in ``after_oldest``, its oldest's in
    ``oldest`` (per-sample flags: a value of the Hessian or linear term not finite),
    or, ``bounds`` given (``(lower, upper)``, per sample), a bound is NaN or one array
    holds both infinities.
    """
    m = every.size
    after = np.concatenate([[0], np.cumsum(after_oldest, dtype=np.int64)])
    a = np.arange(1, m - N + 1)
    bad = (_window_counts(every, N) > 0) | (after[a + N] > after[a + 1]) | oldest[a]
    for values in bounds or ():
        values = values.reshape(m, -1)
        bad |= _window_counts(np.isnan(values).any(axis=1), N) > 0
        up = _window_counts(np.isposinf(values).any(axis=1), N) > 0
        down = _window_counts(np.isneginf(values).any(axis=1), N) > 0
        bad |= up & down
    return bad


def _soft_loads(values: list, lows: list, highs: list, eps, limit: float) -> list | None:
    """:meth:`.qp.LoadCheck.newest` of the soft window in plain floats (same arithmetic):
    the newest sample's variables clipped to their bounds within ten times OSQP's
    tolerance, in N; None beyond ``limit`` or not finite."""
    eps_abs, eps_rel = eps
    tolerance = 10.0 * (eps_abs + eps_rel * max(1.0, max(map(abs, values))))
    loads = []
    for x, a, b in zip(values, lows, highs, strict=True):
        if x < a - tolerance or x > b + tolerance:
            return None
        x = a if a > x else x  # min and max of two as conditionals: the same, NaN included
        x = (b if b < x else x) * LOAD_SCALE
        if not abs(x) <= limit:
            return None
        loads.append(x)
    return loads


def run_soft(mhe, state, rows: dict, kf_loads, record=None):
    """The soft window over a log (module docstring); returns what ``run_ring`` does."""
    s = mhe.settings
    N = s.horizon
    null = mhe.null
    bounded = state.y.size > 0
    inner, oldest, newest = hessian_parts(rows)
    flat = inner.ravel()
    G = rows["g"].ravel()
    W = rows["arrival"]
    bad = bad_windows(
        _not_finite(rows["H"]) | _not_finite(rows["g"]),
        _not_finite(rows["link"]),
        _not_finite(rows["arrival"]),
        (rows["lower"], rows["upper"]) if bounded else None,
        N,
    ).tolist()  # each window's Px: H, g of its samples, the links after its oldest, W_a
    lower_list, upper_list = rows["lower"].tolist(), rows["upper"].tolist()
    eps, limit = (s.solver.eps_abs, s.solver.eps_rel), mhe.load_limit

    def form(i, a, j0, prior, Px, q, low, high) -> bool:
        if j0:  # the log's first samples: inert samples before j0
            current = {name: values[a : a + N] for name, values in rows.items()}
            Px[:] = hessian_values(current, j0, null, False)
            q[:] = linear_term(current, j0, prior, null, False)
            return not finite_data(Px, q, *(() if low is None else (low, high)))
        newest_row = a + N - 1
        Px[10:-14] = flat[14 * a + 14 : 14 * newest_row]
        Px[:10] = oldest[a]
        Px[-14:] = newest[newest_row]
        q[:] = G[4 * a : 4 * newest_row + 4]
        q[:4] -= W[a] @ prior / LOAD_SCALE
        return bad[i]

    def newest_loads(x, newest_row: int) -> list | None:
        return _soft_loads(x[-4:].tolist(), lower_list[newest_row], upper_list[newest_row], eps,
                           limit)  # fmt: skip

    return run_window(mhe, state, rows, kf_loads, record, form=form, newest_loads=newest_loads,
                      size=10 + 14 * (N - 1))  # fmt: skip
