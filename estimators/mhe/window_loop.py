"""The plain MHE window's loop over a log, its per-sample arithmetic handed in.

:func:`~wheelload.estimators.mhe.ring.run_hard` and
:func:`~wheelload.estimators.mhe.soft_window.run_soft` form each window's ``Px`` and
``q`` from terms computed once per log (``form``) and read the newest sample's loads
from the solution (``newest_loads``); the loop around them is this one: the warm start
shifted, a window without data held in closed form
(:func:`~wheelload.estimators.mhe.qp.prior_solution`), the QP loaded and solved
(:class:`~wheelload.estimators.mhe.low_level.HeldSolver`), the filter's estimate
where it is not solved, the lag, the report. ``rows``: each field one array over the
initial window and the log (name -> ``(N + n, ...)``); the window of sample ``i`` is
``[i + 1 : i + 1 + N]``.

Example
-------
>>> run_window(mhe, state, rows, kf_loads, None, form=form, newest_loads=newest, size=2 * N - 1)
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
    prior_solution,
)


def run_window(mhe, state, rows: dict, kf_loads, record, *, form, newest_loads, size: int):
    """The loop (module docstring); returns what ``run_ring`` does.

    ``form(i, a, j0, prior, Px, q, low, high)`` writes the window's ``Px`` (``size``
    values) and ``q`` and returns whether the window is refused as not finite;
    ``newest_loads(x, newest)`` the newest sample's loads [N] from the solution, or None.
    """
    s = mhe.settings
    N, w = s.horizon, mhe.width
    n = len(kf_loads)
    k0 = state.k
    eps = (s.solver.eps_abs, s.solver.eps_rel)
    bounded = state.y.size > 0
    lower, upper = rows["lower"], rows["upper"]
    if bounded:
        low_clamped = np.maximum(lower, -OSQP_INFINITY).ravel()
        high_clamped = np.minimum(upper, OSQP_INFINITY).ravel()
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
    Px, q = np.empty(size), np.empty(N * w)
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
        newest = a + N - 1
        since = 0 if has_data[newest] else since + 1
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
            x_sol = prior_solution(current, j0, history[newest - 1], mhe.null, mhe.hard, x_warm, w)
            y_sol = y_warm.copy()
            code, iters = SOLVED, 0
            x = mhe.check.newest(x_sol[-w:], current)
        else:
            if bounded:
                low, high = lower[a : a + N].ravel(), upper[a : a + N].ravel()
            refused = form(i, a, j0, prior, Px, q, low, high)
            if record is not None:
                recorded = (low, high) if bounded else (None, None)
                record.append(tuple(None if v is None else np.array(v)
                                    for v in (Px, q, *recorded, x_warm, y_warm)))  # fmt: skip
            if refused:
                code, iters = UNSOLVED, 0  # not handed to OSQP: the filter's estimate
            else:
                span = slice(w * a, w * (a + N))
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
                    x = newest_loads(x_sol, newest)
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
