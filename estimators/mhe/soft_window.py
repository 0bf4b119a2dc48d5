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

import time

import numpy as np

from wheelload.estimators.mhe.low_level import (
    HeldSolver,
    finish_run,
    report_arrays,
    samples_without_data,
    window_loads,
)
from wheelload.estimators.mhe.qp import (
    OSQP_INFINITY,
    SOLVED,
    UNSOLVED,
    MheWorkspace,
    finite_data,
    hessian_values,
    linear_term,
    prior_solution,
)
from wheelload.estimators.mhe.terms import LOAD_SCALE

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
    N, w = s.horizon, 4
    n = len(kf_loads)
    k0 = state.k
    eps = (s.solver.eps_abs, s.solver.eps_rel)
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
    lower, upper = rows["lower"], rows["upper"]
    if bounded:
        low_clamped = np.maximum(lower, -OSQP_INFINITY).ravel()
        high_clamped = np.minimum(upper, OSQP_INFINITY).ravel()
    lower_list, upper_list = lower.tolist(), upper.tolist()
    limit = mhe.load_limit
    history = np.empty((N + n, 4))
    history[:N] = state.history
    kfx = np.concatenate([state.kfx, kf_loads])
    x_sol, y_sol, rho = state.x.copy(), state.y.copy(), state.rho
    held = None if k0 == 0 else HeldSolver(mhe.workspace, rho)
    loads, status, iterations, failed_all, solve_time = report_arrays(n)
    reports: list[tuple[int, int, bool]] = []  # status, iterations, fallback per sample
    lag = s.lag
    x_warm = np.empty(N * w)
    y_warm = np.empty_like(y_sol)
    Px, q = np.empty(10 + 14 * (N - 1)), np.empty(N * w)
    has_data = rows["data"].tolist()
    since = samples_without_data(has_data, N)
    perf_counter = time.perf_counter
    low = high = None

    def window(i: int) -> dict:
        return {name: values[i + 1 : i + 1 + N] for name, values in rows.items()}

    for i in range(n):
        start = perf_counter()
        k = k0 + i
        a = i + 1  # the window's oldest sample in the arrays over initial window + log
        newest_row = a + N - 1
        since = 0 if has_data[newest_row] else since + 1
        j0 = N - 1 - k if k < N - 1 else 0
        prior = history[i]  # the oldest estimate
        if k == 0:
            if held is not None:
                held.release()
            mhe.workspace = MheWorkspace(s, w)
            held = HeldSolver(mhe.workspace, rho)
        x_warm[:-w] = x_sol[w:]
        x_warm[-w:] = x_sol[-w:]
        if bounded:
            y_warm[:-w] = y_sol[w:]
            y_warm[-w:] = y_sol[-w:]
        x = None
        if since >= min(k + 1, N):  # no sample of the window has a data term
            current = window(i)
            x_sol = prior_solution(current, j0, history[i + N - 1], null, False, x_warm, w)
            y_sol = y_warm.copy()
            code, iters = SOLVED, 0
            x = mhe.check.newest(x_sol[-w:], current)
        else:
            if bounded:
                low, high = lower[a : a + N].ravel(), upper[a : a + N].ravel()
            if j0:  # the log's first samples: inert samples before j0
                current = window(i)
                Px[:] = hessian_values(current, j0, null, False)
                q[:] = linear_term(current, j0, prior, null, False)
                refused = not finite_data(Px, q, *((low, high) if bounded else ()))
            else:
                refused = bad[i]
                Px[10:-14] = flat[14 * a + 14 : 14 * newest_row]
                Px[:10] = oldest[a]
                Px[-14:] = newest[newest_row]
                q[:] = G[4 * a : 4 * newest_row + 4]
                q[:4] -= W[a] @ prior / LOAD_SCALE
            if record is not None:
                recorded = (low, high) if bounded else (None, None)
                record.append(tuple(None if v is None else np.array(v)
                                    for v in (Px, q, *recorded, x_warm, y_warm)))  # fmt: skip
            if refused:
                code, iters = UNSOLVED, 0  # not handed to OSQP: the filter's estimate
            else:
                span = slice(4 * a, 4 * a + 4 * N)
                code, iters, Px = held.solve(
                    Px, q, (low, high) if bounded else None,
                    (low_clamped[span], high_clamped[span]) if bounded else None,
                    x_warm, y_warm,
                )  # fmt: skip
                if code == SOLVED:
                    solution = held.osqp.solution
                    x_sol = solution.x
                    if bounded:
                        y_sol = solution.y
                    x = _soft_loads(x_sol[-w:].tolist(), lower_list[newest_row],
                                    upper_list[newest_row], eps, limit)  # fmt: skip
            if code != SOLVED:
                x_sol, y_sol = x_warm.copy(), y_warm.copy()
        failed = x is None
        if failed:
            x = mhe.check.fallback(kf_loads[i], history[N + i - 1])
        history[N + i] = x
        if lag and not failed:
            x = window_loads(mhe, x_sol, window(i), kfx[a : a + N], N - 1 - lag, eps, x)
            loads[i] = x  # else the estimate held in history (copied at the end)
        reports.append((code, iters, failed))
        solve_time[i] = perf_counter() - start
    final = finish_run(mhe, held, reports, history, lag, (loads, status, iterations, failed_all),
                       x_sol, window(n - 1), kfx[n : n + N], eps)  # fmt: skip
    return loads, status, iterations, failed_all, solve_time, final
