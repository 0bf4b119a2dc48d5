"""OSQP's solver object driven by the plain window's loops, and what they report.

Shared by the ring buffers (:mod:`~wheelload.estimators.mhe.ring`: the window of one
sample and the hard window) and the soft window (:mod:`~wheelload.estimators.mhe.soft_window`).
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
