"""The Python MHE window against a bare OSQP solve of the same QPs (``wheelload bench mhe``).

The MHE runs a log once recording each sample's QP (Hessian values, linear
term, bounds, warm start); the same QPs are then replayed on a fresh OSQP
problem of the same pattern and settings through the solver object alone
(update what changed, warm-start, solve). The ratio is the window's
bookkeeping cost on top of OSQP's own, per sample, from Python.

Example
-------
>>> rows = window_against_bare_osqp(vehicle, signals, MheSettings(horizon=20), repeats=3)
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from wheelload.estimators import MheSettings, Signals
from wheelload.estimators.mhe.estimator import MovingHorizonEstimator
from wheelload.estimators.mhe.qp import OSQP_INFINITY, MheWorkspace
from wheelload.models import Vehicle


@dataclass(frozen=True, kw_only=True)
class WindowTiming:
    """Per-sample times [us] of one repeat."""

    mhe: float  # mean window update + solve, from the estimator's solve_time
    bare: float  # mean bare OSQP update + warm start + solve of the same QPs
    mhe_median: float
    bare_median: float


def _replay(settings: MheSettings, width: int, record: list) -> np.ndarray:
    """Time each recorded QP on a fresh workspace, driven like the window drives it."""
    solver = MheWorkspace(settings, width).low_level
    times = np.empty(len(record))
    held = None
    for i, (Px, q, low, high, x, y) in enumerate(record):
        start = time.perf_counter()
        if held is None or not np.array_equal(Px, held):
            solver.update_data_mat(P_x=Px, P_i=None, A_x=None, A_i=None)
            held = Px
        if low is None:
            solver.update_data_vec(q=q, l=None, u=None)
        else:
            solver.update_data_vec(
                q=q, l=np.maximum(low, -OSQP_INFINITY), u=np.minimum(high, OSQP_INFINITY)
            )
        solver.warm_start(x, y if y.size else None)
        solver.solve()
        solver.solution.x  # noqa: B018 - read the solution as the window does
        times[i] = time.perf_counter() - start
    return times


def window_against_bare_osqp(
    vehicle: Vehicle, signals: Signals, settings: MheSettings, repeats: int = 3
) -> list[WindowTiming]:
    """Repeated timings of the MHE window and of bare OSQP on the same QPs."""
    mhe = MovingHorizonEstimator(vehicle, settings)
    mhe.run(signals.slice(0, 50))  # builds and warms the mapped terms
    rows = []
    for _ in range(repeats):
        estimate = mhe.run(signals)
        record: list = []
        mhe.qp_record = record
        mhe.run(signals)
        mhe.qp_record = None
        bare = _replay(settings, mhe.width, record)
        solved = estimate.iterations > 0
        mhe_times = estimate.solve_time[solved] * 1e6
        rows.append(
            WindowTiming(
                mhe=float(np.mean(mhe_times)),
                bare=float(np.mean(bare)) * 1e6,
                mhe_median=float(np.median(mhe_times)),
                bare_median=float(np.median(bare)) * 1e6,
            )
        )
    return rows


@dataclass(frozen=True, kw_only=True)
class AssemblyTiming:
    """Per-sample times [us] of one repeat of the extended window's QP assembly."""

    sparse: float  # median: values at the fixed pattern (WindowQP.assemble_values)
    dense: float  # median: the dense n x n matrix read at the pattern (WindowQP.assemble)
    size: int  # QP variables n
    nnz: int  # Hessian values loaded per sample


def assembly_against_dense(
    vehicle: Vehicle, signals: Signals, settings: MheSettings, repeats: int = 3
) -> list[AssemblyTiming]:
    """The robust/bias window's per-sample QP assembly: sparse values against the dense matrix.

    The MHE runs the log once recording each window's arguments; both
    assemblies are then timed on the same windows (the dense one including the
    read-out at the pattern that OSQP needs).
    """
    mhe = MovingHorizonEstimator(vehicle, settings)
    qp = mhe.window_qp
    record: list = []
    sparse = qp.assemble_values

    def recording(*args):
        record.append(args)
        return sparse(*args)

    qp.assemble_values = recording
    mhe.run(signals)
    del qp.assemble_values
    rows = []
    for _ in range(repeats):
        times = np.empty((2, len(record)))
        for i, args in enumerate(record):
            start = time.perf_counter()
            qp.assemble_values(*args)
            middle = time.perf_counter()
            H, _ = qp.assemble(*args)
            H[qp.rows, qp.cols][qp.order]  # noqa: B018 - the values OSQP is given
            times[:, i] = (middle - start, time.perf_counter() - middle)
        rows.append(AssemblyTiming(sparse=float(np.median(times[0])) * 1e6,
                                   dense=float(np.median(times[1])) * 1e6,
                                   size=qp.n, nnz=qp.nnz))  # fmt: skip
    return rows
