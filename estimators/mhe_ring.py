r"""The plain MHE window over a whole log in preallocated ring buffers, updated in place.

:meth:`MovingHorizonEstimator.run` with quadratic losses and no bias states
advances the window here instead of through a new :class:`MheState` per
sample. Every per-sample array of the window lives in a *mirrored* ring of
length :math:`2N`: sample :math:`k` is written at slots :math:`k \bmod N`
and :math:`k \bmod N + N`, so the window, oldest first, is always the
contiguous view ``ring[h + 1 : h + 1 + N]`` (no copy, no shift). The QP's
Hessian values and linear term are written into preallocated arrays with the
same arithmetic as :func:`wheelload.estimators.mhe._hessian_values` and
:func:`~wheelload.estimators.mhe._linear`, and OSQP is driven through its
low-level solver object (``update_data_vec``, ``update_data_mat``,
``warm_start``, ``solve``), skipping the wrapper's result namespace. The
numbers are those of the per-sample state path to the bit (tested).

Example
-------
>>> estimate = MovingHorizonEstimator(vehicle, MheSettings(horizon=20)).run(signals)
"""

from __future__ import annotations

import time

import numpy as np
import osqp

from wheelload.estimators.quiet import quiet_stdout

SOLVED = osqp.SolverStatus.OSQP_SOLVED.value
INFINITY = osqp.constant("OSQP_INFTY")


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


class LowLevelSolver:
    """The window's OSQP problem driven through the solver object, remembering what it holds.

    Same update rules as :class:`wheelload.estimators.mhe._Workspace` (load only
    what differs, bounds clamped to OSQP's infinity as its wrapper does), so the
    solver sees the same data in the same order.
    """

    def __init__(self, workspace) -> None:
        self.workspace = workspace
        self.solver = workspace.solver._solver
        self.Px = workspace.Px.copy()
        self.bounds = (workspace.bounds[0].copy(), workspace.bounds[1].copy())
        self.rho = workspace.rho
        self.polish = workspace.polish

    def solve(self, Px, q, lower, upper, x, y, rho) -> tuple[int, int, float]:
        """Load, warm-start and solve; returns (status, iterations, rho after the solve)."""
        solver = self.solver
        if not (Px == self.Px).all():  # np.array_equal for equal shapes
            solver.update_data_mat(P_x=Px, P_i=None, A_x=None, A_i=None)
            self.Px[:] = Px
        if rho != self.rho:
            self.workspace.solver.update_settings(rho=rho)
        if lower is not None and not (
            (lower == self.bounds[0]).all() and (upper == self.bounds[1]).all()
        ):
            low = np.maximum(lower, -INFINITY)
            high = np.minimum(upper, INFINITY)
            solver.update_data_vec(q=q, l=low, u=high)
            self.bounds = (lower.copy(), upper.copy())
        else:
            solver.update_data_vec(q=q, l=None, u=None)
        solver.warm_start(x, y if y.size else None)
        if self.polish:
            with quiet_stdout():
                solver.solve()
        else:
            solver.solve()
        # OSQP adapts rho during the solve; the window passes back what the solver holds,
        # so it is read once, when the workspace is handed back (release)
        info = solver.info
        return int(info.status_val), int(info.iter), self.rho

    def solution(self) -> tuple[np.ndarray, np.ndarray]:
        """The last solution (OSQP's binding returns a new array on each access)."""
        solution = self.solver.solution
        return solution.x, solution.y

    def release(self) -> None:
        """Hand the remembered values back to the workspace (for :meth:`_Workspace.solve`)."""
        self.rho = self.solver.get_settings().rho
        self.workspace.Px = self.Px.copy()
        self.workspace.bounds = self.bounds
        self.workspace.rho = self.rho


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
        """:func:`wheelload.estimators.mhe._hessian_values` into the buffers (same arithmetic).

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
        """:func:`wheelload.estimators.mhe._linear` into the buffers (same arithmetic).

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
    from wheelload.estimators.mhe import (
        LOAD_SCALE,
        _csc_value_order,
        _prior_solution,
        _Workspace,
    )

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
    if hard:  # n^T W and n^T W n of each arrival weight, as _hessian_values/_linear form them
        for rows_, arrivals in ((parts, arrival), (previous, state.arrival)):
            for j in range(arrivals.shape[0]):
                nW = null @ arrivals[j]
                rows_["nW"][j] = nW
                rows_["nWn"][j, 0] = nW @ null
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
    buffers = HessianBuffers(N, w, _csc_value_order(N, w))
    solver = None if state.k == 0 else LowLevelSolver(mhe.workspace)
    loads = np.empty((n, 4))
    status = np.empty(n, dtype=np.int64)
    iterations = np.empty(n, dtype=np.int64)
    failed_all = np.zeros(n, dtype=bool)
    solve_time = np.empty(n)
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
            mhe.workspace = _Workspace(s, w)
            solver = LowLevelSolver(mhe.workspace)
        x_warm[:-w] = x_sol[w:]
        x_warm[-w:] = x_sol[-w:]
        if bounded:
            y_warm[:-w] = y_sol[w:]
            y_warm[-w:] = y_sol[-w:]
        x = None
        if since >= min(k + 1, N):  # no sample of the window has a data term
            last = history.window[-1]
            x_sol = _prior_solution(window, j0, last, null, hard, x_warm, w)
            y_sol = y_warm.copy()
            code, iters = SOLVED, 0
            x = mhe._loads(x_sol[-w:], window)
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
            code, iters, rho = solver.solve(Px, q, low, high, x_warm, y_warm, rho)
            if code == SOLVED:
                x_sol, y_sol = solver.solution()
                x = mhe._loads(x_sol[-w:], window)
            else:
                x_sol, y_sol = x_warm.copy(), y_warm.copy()
        failed = x is None
        if failed:
            x = np.clip(kf_loads[i], *mhe.load_bounds)
        kfx.push(kf_loads[i])
        history.push(x)
        if lag and not failed:
            j = N - 1 - lag
            x = _window_loads(mhe, x_sol, window, kfx.window, j, eps)
        loads[i] = x
        status[i], iterations[i], failed_all[i] = code, iters, failed
        solve_time[i] = time.perf_counter() - start
    if solver is not None:
        solver.release()
    final_window = {name: view.copy() for name, view in views[ring.head].items()}
    final_kfx = kfx.window.copy()

    def final(j: int) -> np.ndarray:
        return _window_loads(mhe, x_sol, final_window, final_kfx, j, eps)

    return loads, status, iterations, failed_all, solve_time, final


def _window_loads(mhe, x_sol, window, kfx, j, eps) -> np.ndarray:
    """:meth:`MovingHorizonEstimator.window_loads` of the ring's window."""
    w = mhe.width
    block = x_sol[j * w : (j + 1) * w]
    x = mhe._checked(block, window["lower"][j], window["upper"][j], window["xp"][j])
    return np.clip(kfx[j], *mhe.load_bounds) if x is None else x
