"""OSQP's solver object driven by the plain window's loop over a log, and what it reports.

Shared by the loop (:mod:`~wheelload.estimators.mhe.window_loop`) and the windows that
hand it their arithmetic (:mod:`~wheelload.estimators.mhe.ring`,
:mod:`~wheelload.estimators.mhe.soft_window`).
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.mhe.qp import OSQP_INFINITY, check_interrupted
from wheelload.estimators.mhe.quiet import quiet_stdout


class LowLevelSolver:
    """The window's OSQP problem driven through the solver object, remembering what it holds.

    Same update rules as :class:`wheelload.estimators.mhe.qp.MheWorkspace` (load only
    what differs, bounds clamped to OSQP's infinity as its wrapper does), so the
    solver sees the same data in the same order.
    """

    def __init__(self, workspace) -> None:
        self.workspace = workspace
        self.solver = workspace.low_level
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
            low = np.maximum(lower, -OSQP_INFINITY)
            high = np.minimum(upper, OSQP_INFINITY)
            solver.update_data_vec(q=q, l=low, u=high)
            self.bounds = (lower.copy(), upper.copy())
        else:
            solver.update_data_vec(q=q, l=None, u=None)
        solver.warm_start(x, y if y.size else None)
        with quiet_stdout(self.polish):
            solver.solve()
        # OSQP adapts rho during the solve; the window passes back what the solver holds,
        # so it is read once, when the workspace is handed back (release)
        info = solver.info
        check_interrupted(info.status_val)
        return int(info.status_val), int(info.iter), self.rho

    def solution(self) -> tuple[np.ndarray, np.ndarray]:
        """The last solution (OSQP's binding returns a new array on each access)."""
        solution = self.solver.solution
        return solution.x, solution.y

    def release(self) -> None:
        """Hand the remembered values back to the workspace (for :meth:`.qp.MheWorkspace.solve`)."""
        self.rho = self.solver.get_settings().rho
        self.workspace.Px = self.Px.copy()
        self.workspace.bounds = self.bounds
        self.workspace.rho = self.rho


def report_arrays(n: int) -> tuple[np.ndarray, ...]:
    """A log's per-sample outputs: loads (n, 4), status, iterations, fallback, solve time."""
    int64 = np.int64
    return np.empty((n, 4)), np.empty(n, int64), np.empty(n, int64), np.zeros(n, bool), np.empty(n)


def fill_reports(reports, estimates, lag, loads, status, iterations, fallback) -> None:
    """The report arrays of a loop that kept each sample's ``(status, iterations, fallback)``
    in ``reports`` and its estimate in ``estimates`` (n, 4): ``loads`` takes the estimates,
    with a ``lag`` only where the loop fell back (the others it wrote, lagged)."""
    if reports:
        codes, counts, failed = zip(*reports, strict=True)
        status[:], iterations[:], fallback[:] = codes, counts, failed
    if lag:
        loads[fallback] = estimates[fallback]
    else:
        loads[:] = estimates


def window_loads(mhe, x_sol, window, kfx, j, eps, held) -> np.ndarray:
    """:meth:`MovingHorizonEstimator.window_loads` of the ring's window (``held``: the newest
    estimate)."""
    w = mhe.width
    block = x_sol[j * w : (j + 1) * w]
    x = mhe.check.checked(block, window["lower"][j], window["upper"][j], window["xp"][j])
    return mhe.check.fallback(kfx[j], held) if x is None else x


class HeldSolver:
    """The window's OSQP problem in the loop over a log (``window_loop.run_window``): it loads
    only what differs from what it holds (the Hessian values compared from their first),
    swapping the caller's buffer for the one it held instead of copying. The same calls
    in the same order as :meth:`LowLevelSolver.solve`."""

    def __init__(self, workspace, rho: float) -> None:
        self.rho = rho  # the one the state asks for
        self.attach(workspace)

    def attach(self, workspace) -> None:
        """Drive ``workspace`` (a fresh one at a log's first sample)."""
        self.workspace = workspace
        self.low_level = LowLevelSolver(workspace)
        self.osqp = self.low_level.solver
        self.Px, (self.lower, self.upper) = self.low_level.Px, self.low_level.bounds
        self.polish = self.low_level.polish

    def solve(self, Px, q, bounds, clamped, x, y) -> tuple[int, int, np.ndarray]:
        """Load, warm-start and solve: ``(status, iterations, buffer for the next Px)``.

        ``bounds`` ``(lower, upper)`` or None (unbounded); ``clamped`` the same bounds
        clamped to OSQP's infinity, loaded when they differ from those held.
        """
        solver = self.osqp
        if Px[0] != self.Px[0] or not (Px == self.Px).all():
            solver.update_data_mat(P_x=Px, P_i=None, A_x=None, A_i=None)
            Px, self.Px = self.Px, Px  # the buffer just loaded is now the one held
        if self.rho != self.low_level.rho:
            self.workspace.solver.update_settings(rho=self.rho)
        if bounds is not None and not (
            (bounds[0] == self.lower).all() and (bounds[1] == self.upper).all()
        ):
            solver.update_data_vec(q=q, l=clamped[0], u=clamped[1])
            self.lower, self.upper = bounds
        else:
            solver.update_data_vec(q=q, l=None, u=None)
        solver.warm_start(x, None if bounds is None else y)
        if self.polish:
            with quiet_stdout():
                solver.solve()
        else:
            solver.solve()
        info = solver.info
        code = info.status_val
        check_interrupted(code)
        return code, info.iter, Px

    def release(self) -> None:
        """Hand what it holds back to the workspace (:meth:`LowLevelSolver.release`)."""
        self.low_level.Px[:] = self.Px
        self.low_level.bounds = (self.lower.copy(), self.upper.copy())
        self.low_level.release()


def samples_without_data(has_data: list[bool], N: int) -> int:
    """Samples since the newest with a data term in the initial window (``has_data`` of the
    initial window and the log; the initial window's inert samples count as data)."""
    return next((N - 1 - j for j in range(N - 1, -1, -1) if has_data[j]), N)


def finish_run(mhe, held, reports, history, lag, arrays, x_sol, last_window, kfx, eps):
    """After a loop over a log: the solver's values handed back, the report ``arrays``
    (loads, status, iterations, fallback) filled, and ``final(j)``, the loads of sample
    ``j`` of the last window (``last_window``, ``kfx`` its filter estimates) for the
    lagged tail."""
    if held is not None:
        held.release()
    N = len(history) - len(arrays[0])
    fill_reports(reports, history[N:], lag, *arrays)
    final_window = {name: view.copy() for name, view in last_window.items()}
    final_kfx, final_held = kfx.copy(), np.array(history[-1], dtype=float)

    def final(j: int) -> np.ndarray:
        return window_loads(mhe, x_sol, final_window, final_kfx, j, eps, final_held)

    return final
