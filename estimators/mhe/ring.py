r"""The plain MHE window over a whole log in preallocated ring buffers, updated in place.

:meth:`MovingHorizonEstimator.run` with quadratic losses and no bias states
advances the window here instead of through a new :class:`MheState` per
sample. Every per-sample array of the window lives in a *mirrored* ring of
length :math:`2N`: sample :math:`k` is written at slots :math:`k \bmod N`
and :math:`k \bmod N + N`, so the window, oldest first, is always the
contiguous view ``ring[h + 1 : h + 1 + N]`` (no copy, no shift). The QP's
Hessian values and linear term are written into preallocated arrays with the
same arithmetic as :func:`wheelload.estimators.mhe.qp.hessian_values` and
:func:`~wheelload.estimators.mhe.qp.linear_term`, and OSQP is driven through its
low-level solver object (``update_data_vec``, ``update_data_mat``,
``warm_start``, ``solve``), skipping the wrapper's result namespace. The
numbers are those of the per-sample state path to the bit (tested).

A window of more than one sample takes a loop over whole-log arrays instead, every
term known before it formed once per sample: the hard window :func:`run_hard`, the
soft one :func:`~wheelload.estimators.mhe.soft_window.run_soft`; the ring buffers
serve the one-sample window.

Example
-------
>>> estimate = MovingHorizonEstimator(vehicle, MheSettings(horizon=20)).run(signals)
"""

from __future__ import annotations

import math
import time

import numpy as np

from wheelload.estimators.mhe.low_level import (
    HeldSolver,
    LowLevelSolver,
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
    csc_value_order,
    finite_data,
    prior_solution,
)
from wheelload.estimators.mhe.soft_window import bad_windows, run_soft
from wheelload.estimators.mhe.terms import LOAD_SCALE


class MirroredRing:
    """``(2N, *shape)`` buffer whose window of the last ``N`` rows is a contiguous view."""

    def __init__(self, initial: np.ndarray) -> None:
        N = initial.shape[0]
        self.N = N
        self.data = np.concatenate([initial, initial]).astype(float)
        self.head = 0  # slot of the oldest sample

    def push(self, value) -> None:
        """Drop the oldest row and append ``value`` as the newest (in place)."""
        h = self.head
        self.data[h] = value
        self.data[h + self.N] = value
        self.head = h + 1 if h + 1 < self.N else 0

    @property
    def window(self) -> np.ndarray:
        """The last ``N`` rows, oldest first (a view)."""
        return self.data[self.head : self.head + self.N]


class HessianBuffers:
    """Preallocated arrays for the window's Hessian values and linear term."""

    def __init__(self, N: int, width: int, order: np.ndarray) -> None:
        self.N, self.w = N, width
        self.order = order
        self.source = np.empty(N * width * width + (N - 1) * width)
        self.blocks = self.source[: N * width * width].reshape(N, width, width)
        self.couplings = self.source[N * width * width :].reshape(N - 1, width)
        self.diagonal = np.empty(N)
        self.scaled = np.empty((N, width, width))
        self.eye = np.eye(width)
        self.values = np.empty(order.size)
        self.q = np.empty((N, width))

    def hessian(self, H, link, arrival_j0, j0, null, hard, nWn=None) -> np.ndarray:
        """:func:`wheelload.estimators.mhe.qp.hessian_values` into the buffers (same
        arithmetic).

        ``nWn`` (hard): :math:`n^\top W n` of the arrival weight, computed beforehand.
        """
        diagonal = self.diagonal
        diagonal[:] = link
        diagonal[0] = 0.0
        diagonal[:-1] += link[1:]
        if hard:
            blocks = self.source[: self.N]
            np.add(H[:, 0, 0], diagonal, out=blocks)
            blocks[j0] += nWn
            np.negative(link[1:], out=self.source[self.N : 2 * self.N - 1])
            np.take(self.source[: 2 * self.N - 1], self.order, out=self.values)
            return self.values
        np.multiply(diagonal[:, None, None], self.eye, out=self.scaled)
        np.add(H, self.scaled, out=self.blocks)
        self.blocks[j0] += arrival_j0
        self.couplings[:] = -link[1:, None]
        np.take(self.source, self.order, out=self.values)
        return self.values

    def linear(self, g, j0, prior, arrival_j0, drift, xp_j0, null, hard, scale) -> np.ndarray:
        """:func:`wheelload.estimators.mhe.qp.linear_term` into the buffers (same arithmetic).

        Hard: ``arrival_j0`` is :math:`n^\top W` (computed beforehand), soft: :math:`W`.
        """
        q = self.q
        q[:] = g
        if hard:
            d = drift[1:]
            q[1:, 0] += d
            q[:-1, 0] -= d
            q[j0, 0] += arrival_j0 @ (xp_j0 - prior) / scale
        else:
            q[j0] -= arrival_j0 @ prior / scale
        return q.ravel()


def run_ring(mhe, state, H, g, link, xp, lower, upper, kf_loads, arrival, record=None):
    """The plain window over a log (see module docstring).

    ``H, g, link, xp, lower, upper`` are the terms Function's outputs per
    sample, ``kf_loads`` the fallback filter's estimates, ``arrival`` the
    arrival weights. Returns ``(loads, status, iterations, fallback,
    solve_time, final)`` with ``final`` the window's last solution for the
    lagged tail: a callable ``final(j) -> loads`` of window sample ``j``.
    ``record``, a list, receives each solved QP's data ``(Px, q, l, u, x, y)``
    (``wheelload bench mhe`` replays them on bare OSQP).
    """
    s = mhe.settings
    N, w = s.horizon, mhe.width
    n = H.shape[0]
    hard, null = mhe.hard, mhe.null
    k0 = state.k
    eps = (s.solver.eps_abs, s.solver.eps_rel)
    fields = {  # one packed row per sample: (name, width, shape of the window view)
        "H": (w * w, (w, w)), "g": (w, (w,)), "link": (1, ()), "drift": (1, ()),
        "xp": (4, (4,)), "lower": (w, (w,)), "upper": (w, (w,)), "arrival": (16, (4, 4)),
        "data": (1, ()), "nW": (4, (4,)), "nWn": (1, ()),
    }  # fmt: skip
    columns, offset = {}, 0
    for name, (size, _) in fields.items():
        columns[name] = slice(offset, offset + size)
        offset += size
    H = H.reshape(n, w * w)
    links = np.where(np.arange(k0, k0 + n) > 0, link[:, 0], 0.0)
    drifts = np.zeros(n)
    if hard:  # the random walk's pull along the warp vector, as in _advance
        before = np.vstack([state.xp[-1:], xp[:-1]])
        for i in range(n):
            drifts[i] = links[i] / LOAD_SCALE * float(null @ (xp[i] - before[i]))
    rows = np.empty((n, offset))
    parts = {"H": H, "g": g, "link": links[:, None], "drift": drifts[:, None], "xp": xp,
             "lower": lower, "upper": upper, "arrival": arrival.reshape(n, 16),
             "data": H.any(axis=1)[:, None], "nW": np.zeros((n, 4)),
             "nWn": np.zeros((n, 1))}  # fmt: skip
    initial = np.empty((N, offset))
    previous = {"H": state.H.reshape(N, w * w), "g": state.g, "link": state.link[:, None],
             "drift": state.drift[:, None], "xp": state.xp, "lower": state.lower,
             "upper": state.upper, "arrival": state.arrival.reshape(N, 16),
             "data": state.H.reshape(N, -1).any(axis=1)[:, None], "nW": np.zeros((N, 4)),
             "nWn": np.zeros((N, 1))}  # fmt: skip
    if hard:  # n^T W and n^T W n of each arrival weight, as qp.hessian_values/linear_term form them
        for rows_, arrivals in ((parts, arrival), (previous, state.arrival)):
            for j in range(arrivals.shape[0]):
                nW = null @ arrivals[j]
                rows_["nW"][j] = nW
                rows_["nWn"][j, 0] = nW @ null
    if N > 1:  # each window its own loop over whole-log arrays (the arithmetic hoisted)
        whole = {
            name: np.concatenate([previous[name], parts[name]]).reshape(N + n, *shape)
            for name, (_, shape) in fields.items()
        }
        if hard:
            return run_hard(mhe, state, whole, kf_loads, record)
        return run_soft(mhe, state, whole, kf_loads, record)
    for name in fields:
        rows[:, columns[name]] = parts[name]
        initial[:, columns[name]] = previous[name]
    ring = MirroredRing(initial)
    views = [
        {
            name: ring.data[h : h + N, columns[name]].reshape((N, *fields[name][1]))
            for name in fields
        }
        for h in range(N)
    ]
    history = MirroredRing(state.history)
    kfx = MirroredRing(state.kfx)
    x_sol, y_sol, rho = state.x.copy(), state.y.copy(), state.rho
    bounded = state.y.size > 0
    buffers = HessianBuffers(N, w, csc_value_order(N, w))
    solver = None if state.k == 0 else LowLevelSolver(mhe.workspace)
    loads, status, iterations, failed_all, solve_time = report_arrays(n)
    lag = s.lag
    x_warm = np.empty(N * w)
    y_warm = np.empty_like(y_sol)
    has_data = parts["data"][:, 0].tolist()
    # samples since the newest with data (the initial window's inert samples count as data:
    # the test below only looks at the min(k + 1, N) samples of the log)
    flags = previous["data"][:, 0].tolist()
    since = next((N - 1 - j for j in range(N - 1, -1, -1) if flags[j]), N)
    for i in range(n):
        start = time.perf_counter()
        k = k0 + i
        since = 0 if has_data[i] else since + 1
        ring.push(rows[i])
        window = views[ring.head]
        j0 = max(0, N - 1 - k)
        prior = history.data[history.head]  # the oldest estimate (read before the push)
        if k == 0:
            if solver is not None:
                solver.release()
            mhe.workspace = MheWorkspace(s, w)
            solver = LowLevelSolver(mhe.workspace)
        x_warm[:-w] = x_sol[w:]
        x_warm[-w:] = x_sol[-w:]
        if bounded:
            y_warm[:-w] = y_sol[w:]
            y_warm[-w:] = y_sol[-w:]
        x = None
        if since >= min(k + 1, N):  # no sample of the window has a data term
            last = history.window[-1]
            x_sol = prior_solution(window, j0, last, null, hard, x_warm, w)
            y_sol = y_warm.copy()
            code, iters = SOLVED, 0
            x = mhe.check.newest(x_sol[-w:], window)
        else:
            Px = buffers.hessian(window["H"], window["link"], window["arrival"][j0], j0, null,
                                 hard, window["nWn"][j0])  # fmt: skip
            q = buffers.linear(
                window["g"], j0, prior, window["nW"][j0] if hard else window["arrival"][j0],
                window["drift"], window["xp"][j0], null, hard, LOAD_SCALE,
            )  # fmt: skip
            low = window["lower"].ravel() if bounded else None
            high = window["upper"].ravel() if bounded else None
            if record is not None:
                record.append(tuple(None if a is None else np.array(a)
                                    for a in (Px, q, low, high, x_warm, y_warm)))  # fmt: skip
            if finite_data(Px, q, *((low, high) if bounded else ())):
                code, iters, rho = solver.solve(Px, q, low, high, x_warm, y_warm, rho)
            else:
                code, iters = UNSOLVED, 0
            if code == SOLVED:
                x_sol, y_sol = solver.solution()
                x = mhe.check.newest(x_sol[-w:], window)
            else:
                x_sol, y_sol = x_warm.copy(), y_warm.copy()
        failed = x is None
        if failed:
            x = mhe.check.fallback(kf_loads[i], history.window[-1])
        kfx.push(kf_loads[i])
        history.push(x)
        if lag and not failed:
            j = N - 1 - lag
            x = window_loads(mhe, x_sol, window, kfx.window, j, eps, x)
        loads[i] = x
        status[i], iterations[i], failed_all[i] = code, iters, failed
        solve_time[i] = time.perf_counter() - start
    if solver is not None:
        solver.release()
    final_window = {name: view.copy() for name, view in views[ring.head].items()}
    final_kfx = kfx.window.copy()
    final_held = history.window[-1].copy()

    def final(j: int) -> np.ndarray:
        return window_loads(mhe, x_sol, final_window, final_kfx, j, eps, final_held)

    return loads, status, iterations, failed_all, solve_time, final


def _hard_loads(
    omega: float, low: float, high: float, xp, null, bounds, eps, limit: float
) -> list | None:
    r""":meth:`.qp.LoadCheck.newest` of the hard window in plain floats (same arithmetic).

    :math:`\omega` clipped to its interval within ten times OSQP's tolerance, then
    :math:`x = \bar x + n\,\omega` clipped to the load bounds within rounding (a
    collapsed interval, ``low == high``: clipped); None beyond ``limit`` or not finite.
    """
    eps_abs, eps_rel = eps
    size = abs(omega)  # min and max of two as conditionals: the same values, NaN included
    tolerance = 10.0 * (eps_abs + eps_rel * (size if size > 1.0 else 1.0))
    if omega < low - tolerance or omega > high + tolerance:
        return None
    omega = low if low > omega else omega
    scaled = (high if high < omega else omega) * LOAD_SCALE
    x = [a + b * scaled for a, b in zip(xp, null)]
    tolerance = math.inf if low == high else 10.0 * (1e-9 + 1e-12 * max(1.0, max(map(abs, x))))
    lowest, highest = bounds
    clipped = []
    for value in x:
        if value < lowest - tolerance or value > highest + tolerance or not abs(value) <= limit:
            return None
        value = lowest if lowest > value else value
        clipped.append(highest if highest < value else value)
    return clipped


def run_hard(mhe, state, rows: dict, kf_loads, record=None):
    r"""The hard window (one warp variable :math:`\omega` per sample) over a log.

    The same numbers and OSQP calls as :func:`run_ring`'s loop, with the
    window's arithmetic hoisted out of it: every per-sample term is known
    before the loop, so each field is one array over the initial window and
    the log (``rows``: name -> ``(N + n, ...)``) and the window of sample
    ``i`` is the view ``[i + 1 : i + 1 + N]``. The tridiagonal Hessian's
    interior values :math:`H_j + (\ell_j + \ell_{j+1})` and couplings
    :math:`-\ell_j`, and the linear term's interior :math:`(g_j + d_j) -
    d_{j+1}`, are formed once per sample, interleaved in CSC order, so each
    window's ``Px`` and ``q`` are one copy plus their two end values. Bounds
    are clamped to OSQP's infinity once. Only the estimate-dependent prior term
    is computed per sample.
    """
    s = mhe.settings
    N = s.horizon
    n = len(kf_loads)
    k0 = state.k
    eps = (s.solver.eps_abs, s.solver.eps_rel)
    H0, L, D, G = rows["H"][:, 0, 0], rows["link"], rows["drift"], rows["g"][:, 0]
    # Px in CSC order: [d_0, -l_1, d_1, ..., -l_{N-1}, d_{N-1}] = interleaved (-l_j, d_j)[1:]
    interleaved = np.empty((N + n, 2))
    interleaved[:, 0] = -L
    interleaved[:-1, 1] = H0[:-1] + (L[:-1] + L[1:])
    interleaved[-1, 1] = 0.0  # the log's newest sample is always last in its window
    interleaved = interleaved.ravel()
    interior = np.empty(N + n)
    interior[:-1] = (G[:-1] + D[:-1]) - D[1:]
    interior[-1] = 0.0
    # a window's end values once its arrival weight is on its oldest sample (j0 = 0)
    first_px = ((H0[:-1] + (0.0 + L[1:])) + rows["nWn"][:-1]).tolist()
    last_px = (H0 + L).tolist()
    first_q, last_q = (G[:-1] - D[1:]).tolist(), (G + D).tolist()
    bounded = state.y.size > 0
    finite = np.isfinite
    bad = bad_windows(
        ~(finite(H0) & finite(G)),
        ~(finite(L) & finite(D)),
        ~(finite(rows["nWn"]) & finite(rows["nW"]).all(axis=1) & finite(rows["xp"]).all(axis=1)),
        (rows["lower"], rows["upper"]) if bounded else None,
        N,
    ).tolist()  # each window's Px and q: H, g of its samples, links and drifts after its
    # oldest, the arrival weight's n^T W and n^T W n and the xp of its oldest
    if bounded:
        lower, upper = rows["lower"][:, 0], rows["upper"][:, 0]
        low_clamped = np.maximum(lower, -OSQP_INFINITY)
        high_clamped = np.minimum(upper, OSQP_INFINITY)
    H0l, Ll, Dl, Gl = H0.tolist(), L.tolist(), D.tolist(), G.tolist()
    lower_list = rows["lower"][:, 0].tolist()
    upper_list = rows["upper"][:, 0].tolist()
    xp_list = rows["xp"].tolist()
    nW, nWn, xp = rows["nW"], rows["nWn"].tolist(), rows["xp"]
    null = mhe.null.tolist()
    bounds = mhe.load_bounds
    history = np.empty((N + n, 4))
    history[:N] = state.history
    kfx = np.concatenate([state.kfx, kf_loads])
    x_sol, y_sol, rho = state.x.copy(), state.y.copy(), state.rho
    held = None if k0 == 0 else HeldSolver(mhe.workspace, rho)
    loads, status, iterations, failed_all, solve_time = report_arrays(n)
    reports: list[tuple[int, int, bool]] = []  # status, iterations, fallback per sample
    lag = s.lag
    x_warm = np.empty(N)
    y_warm = np.empty_like(y_sol)
    Px, q = np.empty(2 * N - 1), np.empty(N)
    has_data = rows["data"].tolist()
    since = samples_without_data(has_data, N)
    perf_counter = time.perf_counter

    def window(i: int) -> dict:
        return {name: values[i + 1 : i + 1 + N] for name, values in rows.items()}

    for i in range(n):
        start = perf_counter()
        k = k0 + i
        a = i + 1  # the window's oldest sample in the arrays over initial window + log
        since = 0 if has_data[a + N - 1] else since + 1
        j0 = N - 1 - k if k < N - 1 else 0
        prior = history[i]  # the oldest estimate
        if k == 0:
            if held is not None:
                held.release()
            mhe.workspace = MheWorkspace(s, 1)
            held = HeldSolver(mhe.workspace, rho)
        x_warm[:-1] = x_sol[1:]
        x_warm[-1] = x_sol[-1]
        if bounded:
            y_warm[:-1] = y_sol[1:]
            y_warm[-1] = y_sol[-1]
        x = None
        newest = a + N - 1
        if since >= min(k + 1, N):  # no sample of the window has a data term
            current = window(i)
            x_sol = prior_solution(current, j0, history[i + N - 1], mhe.null, True, x_warm, 1)
            y_sol = y_warm.copy()
            code, iters = SOLVED, 0
            x = mhe.check.newest(x_sol[-1:], current)
        else:
            Px[:] = interleaved[2 * a + 1 : 2 * a + 2 * N]
            q[:] = interior[a : a + N]
            if j0 == 0:
                Px[0], Px[-1] = first_px[a], last_px[newest]
                q[0], q[-1] = first_q[a], last_q[newest]
            else:  # the log's first samples: inert samples before j0
                Px[0] = H0l[a] + (0.0 + Ll[a + 1])
                Px[-1] = H0l[newest] + Ll[newest]
                Px[2 * j0] += nWn[a + j0]
                q[0] = Gl[a] - Dl[a + 1]
                q[-1] = Gl[newest] + Dl[newest]
            q[j0] += nW[a + j0] @ (xp[a + j0] - prior) / LOAD_SCALE
            if bounded:
                low, high = lower[a : a + N], upper[a : a + N]
            if record is not None:
                recorded = (low, high) if bounded else (None, None)
                record.append(tuple(None if v is None else np.array(v)
                                    for v in (Px, q, *recorded, x_warm, y_warm)))  # fmt: skip
            refused = (
                bad[i] if j0 == 0 else not finite_data(Px, q, *((low, high) if bounded else ()))
            )
            if refused:
                code, iters = UNSOLVED, 0  # not handed to OSQP: the filter's estimate
            else:
                code, iters, Px = held.solve(
                    Px, q, (low, high) if bounded else None,
                    (low_clamped[a : a + N], high_clamped[a : a + N]) if bounded else None,
                    x_warm, y_warm,
                )  # fmt: skip
                if code == SOLVED:
                    solution = held.osqp.solution
                    x_sol = solution.x
                    if bounded:
                        y_sol = solution.y
                    x = _hard_loads(float(x_sol[-1]), lower_list[newest], upper_list[newest],
                                    xp_list[newest], null, bounds, eps, mhe.load_limit)  # fmt: skip
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
