r"""What the MHE carries between samples and what it reports: state, sample terms, estimate.

:class:`MheState` is the window of Rao, Rawlings & Lee's (2001) moving horizon, the last
:math:`N` samples' QP terms (Siegloff & Choi eq. 12-17, see
:mod:`~wheelload.estimators.mhe.terms`) plus the fallback filter's state, the previous
estimates (the arrival prior :math:`\bar x`), the warm start and OSQP's :math:`\rho`.
:class:`SampleTerms` is one sample's contribution, :class:`MheEstimate` the log's report.

Example
-------
>>> state = mhe.initial_state(dt=0.01)
>>> state.history[0]  # the arrival prior of the next window
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wheelload.estimators.kf.two_stage import FilterState, flags_from_used
from wheelload.estimators.result import Estimate, StepFlag

__all__ = [
    "MheEstimate",
    "MheState",
    "SampleTerms",
    "estimate_from_reports",
    "mhe_estimate",
    "shift",
]


@dataclass(frozen=True, kw_only=True, eq=False, repr=False)  # the one-line Estimate repr
class MheEstimate(Estimate):
    """:class:`Estimate` plus the solver's per-sample report."""

    status: np.ndarray  # (n,) OSQP status value (1 = solved; 0 = interval rejected)
    iterations: np.ndarray  # (n,) ADMM iterations
    fallback: np.ndarray  # (n,) True where the Kalman estimate was used
    solve_time: np.ndarray  # (n,) s, wall time of the sample's QP update and solve
    lag: int = 0  # row i holds the estimate of sample i made when sample i + lag arrived
    bias: np.ndarray | None = None  # (n, nb) travel offsets FL..RR [m] if any, then ax/ay biases

    def to_pandas(self):
        frame = super().to_pandas()
        frame["solver_status"] = self.status
        frame["iterations"] = self.iterations
        frame["fallback"] = self.fallback
        frame["solve_time"] = self.solve_time
        frame["lag"] = self.lag
        if self.bias is not None:
            for i in range(self.bias.shape[1]):
                frame[f"bias_{i}"] = self.bias[:, i]
        return frame


@dataclass(frozen=True, kw_only=True, eq=False)
class MheState:
    """Explicit MHE state: the window of per-sample QP terms and what carries between samples.

    The window holds the last :math:`N` samples, oldest first; before the
    log's first samples it is padded with inert ones (unit Hessian, zero
    terms, bounds 0). Terms are in the QP's units (see :mod:`~wheelload.estimators.mhe.terms`).
    """

    k: int  # samples taken
    cost: float  # QP cost scale c from the nominal interval
    steady: np.ndarray  # (4, 4) steady-state arrival weight (used with Arrival.STEADY_STATE)
    kf: FilterState  # the fallback filter (two-stage or projection KF)
    H: np.ndarray  # (N, w, w) Hessian blocks without process terms
    g: np.ndarray  # (N, w) linear terms
    link: np.ndarray  # (N,) random-walk weight to the sample before (0 for the log's first)
    drift: np.ndarray  # (N,) hard: the random walk's pull link n^T (xp_j - xp_{j-1}) / s
    xp: np.ndarray  # (N, 4) hard: A^+ b [N]; soft: zeros
    lower: np.ndarray  # (N, w) bounds of the QP variables
    upper: np.ndarray  # (N, w)
    arrival: np.ndarray  # (N, 4, 4) arrival weight for a window starting at the sample
    history: np.ndarray  # (N, 4) estimates of the N samples before [N]; the prior is row 0
    x: np.ndarray  # (N w,) primal warm start (the last solution)
    y: np.ndarray  # (m,) dual warm start
    rho: float  # OSQP's step size after the last solve
    kfx: np.ndarray  # (N, 4) the filter's estimates of the window's samples (lagged fallback)
    samples: tuple = ()  # extended window: the WindowSample of each sample
    local: tuple = ()  # extended window: each sample's (H, g) of its data rows
    beta: np.ndarray = field(default_factory=lambda: np.zeros(0))  # bias estimate
    beta_info: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # its information


@dataclass(frozen=True, eq=False)
class SampleTerms:
    """One sample's outputs of the terms Function plus the fallback filter's (1-D arrays)."""

    H: np.ndarray
    g: np.ndarray
    link: float
    xp: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    b: np.ndarray
    used: np.ndarray
    kf: FilterState  # the filter's state after the sample
    std: np.ndarray  # the filter's standard deviations
    rows: tuple | None = None  # extended window: (z, Jd, Ba, ls, lc) of residual_function


def mhe_estimate(
    t, loads, std, b, used, A, *, status, iterations, fallback, solve_time, lag, bias
) -> MheEstimate:
    r"""The :class:`MheEstimate` of the loads :math:`x`, with the residual :math:`b - A x`.

    ``std``, ``b`` and ``used`` are the filter's standard deviations, the equilibrium's
    right-hand sides and the rows' use flags per sample; the rest is the solver's report.
    """
    used = np.asarray(used).reshape(-1, len(StepFlag.update_flags()))
    return MheEstimate(
        t=t,
        loads=loads,
        std=np.asarray(std).reshape(-1, 4),
        residual=np.asarray(b).reshape(-1, 3) - loads @ A.T,
        flags=flags_from_used(used.T),
        status=status,
        iterations=iterations,
        fallback=fallback,
        solve_time=solve_time,
        lag=lag,
        bias=bias,
    )


def estimate_from_reports(t: np.ndarray, reports: list, A: np.ndarray, lag: int = 0) -> MheEstimate:
    """The :class:`MheEstimate` of the window's per-sample reports (``MovingHorizonEstimator``).

    Each report: (loads, :class:`SampleTerms`, status, iterations, fallback, solve time, bias).
    """
    terms = [r[1] for r in reports]
    return mhe_estimate(
        t,
        np.array([r[0] for r in reports]).reshape(-1, 4),
        np.array([s.std for s in terms]),
        np.array([s.b for s in terms]),
        np.array([s.used for s in terms]),
        A,
        status=np.array([r[2] for r in reports], dtype=np.int64),
        iterations=np.array([r[3] for r in reports], dtype=np.int64),
        fallback=np.array([r[4] for r in reports], dtype=bool),
        solve_time=np.array([r[5] for r in reports], dtype=float),
        lag=lag,
        bias=None if reports[0][6] is None else np.array([r[6] for r in reports]),
    )


def shift(window: np.ndarray, newest) -> np.ndarray:
    """``window`` moved one sample on, ``newest`` appended at the end."""
    return np.concatenate([window[1:], np.asarray(newest, dtype=float)[None]])
