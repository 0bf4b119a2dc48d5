r"""Moving-horizon estimation of the four wheel loads, one OSQP quadratic program per sample.

Window of the last :math:`N` samples :math:`x_{k-N+1..k}` (Rao, Rawlings &
Lee 2001) with the random walk (Siegloff & Choi eq. 12), the suspension
pseudo-measurements (eq. 13) and the equilibrium (eq. 14-17):

.. math::
    \min_{x} \; \|x_{k-N+1} - \bar x\|^2_{\Pi^{-1}}
      + \sum_{j > k-N+1} \|x_j - x_{j-1}\|^2_{Q_j^{-1}}
      + \sum_j \|z_j - x_j\|^2_{R_{s,j}^{-1}}
      + \sum_j \|b_j - A x_j\|^2_{R_{c,j}^{-1}}
    \quad \text{s.t.} \quad 0 \le x_j \le F_{max}

:attr:`Constraint.SOFT` keeps the last term; :attr:`Constraint.HARD` drops
it and imposes :math:`A x_j = b_j`. Rank :math:`A = 3`, so then
:math:`x_j = A^+ b_j + n\,\omega_j` with :math:`n` the unit null vector of
:math:`A` (the diagonal "warp" mode): the QP is in the :math:`N` warp
amplitudes only, the equality holds by construction, and the bounds become
one interval per sample.

The arrival prior is the MHE estimate at :math:`k-N` with
:math:`\Pi = P_{k-N} + Q`, :math:`P` from the Kalman covariance recursion
(the two-stage KF for soft, the projection KF with :math:`W = P^{-1}` for
hard constraints) or its steady state. With :math:`N = 1`, soft constraints
and no bounds the QP's minimiser is the two-stage KF estimate.

The QP is set up once per log with a fixed sparsity; each sample updates
``q`` (and ``l, u`` for hard constraints), the Hessian values only when they
change (arrival weight, sample interval, missing inputs), warm-starts with
the shifted previous solution and solves. A sample whose QP is not solved
(status other than *solved*, or a bound violated by more than the solver
tolerance) takes the Kalman estimate, clipped to the bounds, and is marked
in :attr:`MheEstimate.fallback`. Bounds hold exactly: the solver's
violations, once checked to be within tolerance, are clipped.

Example
-------
>>> mhe = MovingHorizonEstimator(vehicle, MheSettings(horizon=10, bounded=True))
>>> estimate = mhe.run(read_log("drive.csv"))
"""

from __future__ import annotations

import enum
import math
import time
from dataclasses import dataclass, field

import numpy as np
import osqp
import scipy.sparse as sp

from wheelload.estimators.projection import ProjectionKF, Weighting
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import (
    TwoStageKF,
    input_matrix,
    sample_intervals,
)
from wheelload.models import Vehicle, equilibrium_function, suspension_function

LOAD_SCALE = 1000.0  # N: the QP's variables are in kN
SOLVED = osqp.SolverStatus.OSQP_SOLVED.value


class Constraint(enum.Enum):
    """How the equilibrium :math:`A x = b` enters the window."""

    SOFT = "soft"  # penalty weighted by R_c^-1 (eq. 17)
    HARD = "hard"  # equality on every sample


class Arrival(enum.Enum):
    """Covariance :math:`\\Pi` of the arrival prior."""

    KALMAN = "kalman"  # P_{k-N} + Q from the filter's covariance recursion
    STEADY_STATE = "steady-state"  # the recursion's fixed point at the median interval


@dataclass(frozen=True, kw_only=True)
class SolverSettings:
    """OSQP settings (tolerances in the QP's kN units, cost scaled to unit Hessian diagonal)."""

    eps_abs: float = 1e-6
    eps_rel: float = 1e-6
    max_iter: int = 500
    polish: bool = False
    check_termination: int = 5
    adaptive_rho_interval: int = 25  # fixed, so that Python and generated C iterate alike

    def __post_init__(self) -> None:
        if not (self.eps_abs > 0 and self.eps_rel >= 0):
            raise ValueError(f"eps_abs must be > 0 and eps_rel >= 0, got {self}")
        if self.max_iter < 1 or self.check_termination < 1:
            raise ValueError(f"max_iter and check_termination must be >= 1, got {self}")


@dataclass(frozen=True, kw_only=True)
class MheSettings:
    """Window length, constraint handling, bounds and arrival cost of the MHE."""

    horizon: int = 10
    constraint: Constraint = Constraint.SOFT
    bounded: bool = False
    max_load: float = math.inf  # N, upper bound when ``bounded``
    arrival: Arrival = Arrival.KALMAN
    solver: SolverSettings = field(default_factory=SolverSettings)

    def __post_init__(self) -> None:
        if not isinstance(self.horizon, int) or self.horizon < 1:
            raise ValueError(f"horizon must be an integer >= 1, got {self.horizon!r}")
        if not isinstance(self.constraint, Constraint):
            raise TypeError(f"constraint must be a Constraint, got {self.constraint!r}")
        if not isinstance(self.arrival, Arrival):
            raise TypeError(f"arrival must be an Arrival, got {self.arrival!r}")
        if not self.max_load > 0:
            raise ValueError(f"max_load must be > 0, got {self.max_load}")

    def label(self) -> str:
        bounds = ", bounded" if self.bounded else ""
        return f"MHE N={self.horizon} ({self.constraint.value}{bounds})"


@dataclass(frozen=True, kw_only=True, eq=False)
class MheEstimate(Estimate):
    """:class:`Estimate` plus the solver's per-sample report."""

    status: np.ndarray  # (n,) OSQP status value (1 = solved)
    iterations: np.ndarray  # (n,) ADMM iterations
    fallback: np.ndarray  # (n,) True where the Kalman estimate was used
    solve_time: np.ndarray  # (n,) s, wall time of the sample's QP update and solve

    def to_pandas(self):
        frame = super().to_pandas()
        frame["status"] = self.status
        frame["iterations"] = self.iterations
        frame["fallback"] = self.fallback
        frame["solve_time"] = self.solve_time
        return frame


@dataclass(frozen=True, eq=False)
class LogTerms:
    """Per-sample data of a log, padded with ``N - 1`` inert samples in front.

    Soft: ``H`` (4x4 Hessian block without process terms), ``g`` (4) linear
    term; hard: scalars in the warp amplitude. ``link`` is the weight of the
    random-walk term joining a sample to the one before (0 for the first),
    ``arrival`` the arrival weight :math:`\\Pi^{-1}` for a window starting
    at the sample. All scaled to the QP's units.
    """

    H: np.ndarray
    g: np.ndarray
    drift: np.ndarray  # hard: c s w_q n^T (A^+ b_j - A^+ b_{j-1}), the random walk's pull
    link: np.ndarray
    arrival: np.ndarray
    lower: np.ndarray  # (.., 4) soft or (..,) hard: bounds of the QP variable
    upper: np.ndarray
    particular: np.ndarray  # (.., 4): A^+ b (hard) or zeros (soft)


class MovingHorizonEstimator:
    """Moving-horizon wheel-load estimator on OSQP (see module docstring).

    Parameters
    ----------
    vehicle
        Vehicle parameters and filter tuning.
    settings
        Window length, constraints, bounds, arrival cost and solver settings.
    static
        Static wheel loads [N]; default: the vehicle file's.
    """

    def __init__(
        self,
        vehicle: Vehicle,
        settings: MheSettings | None = None,
        *,
        static: np.ndarray | None = None,
    ) -> None:
        self.settings = settings or MheSettings()
        self.name = self.settings.label()
        hard = self.settings.constraint is Constraint.HARD
        self.filter = (
            ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY, static=static)
            if hard
            else TwoStageKF(vehicle, static=static)
        )
        self.p = self.filter.p
        self.tuning = self.filter.tuning
        self._suspension = suspension_function()
        self._equilibrium = equilibrium_function()
        A, _ = self._equilibrium(np.zeros(3), 0.0, self.p)
        self.A = np.asarray(A)
        self.null = _null_vector(self.A)
        self.pinv = np.linalg.pinv(self.A)

    # -- per-log data ------------------------------------------------------------------------

    def model_terms(self, signals: Signals) -> tuple[np.ndarray, np.ndarray]:
        """Pseudo-measurements ``z`` (n, 4) and equilibrium right-hand sides ``b`` (n, 3).

        Evaluated with the model Functions mapped over the log; missing inputs
        are replaced by zero here and masked out by the caller.
        """
        n = len(signals)
        u = np.nan_to_num(input_matrix(signals), nan=0.0, posinf=0.0, neginf=0.0)
        z = self._suspension.map(n)(u[0:4], u[4:8], self.p)
        _, b = self._equilibrium.map(n)(u[8:11], u[11:12], self.p)
        return np.asarray(z).T, np.asarray(b).T

    def cost_factor(self, dt: float) -> float:
        """Cost scale :math:`c`: the QP's Hessian :math:`c s^2 H` has diagonal entries near one."""
        q, r_s = self.tuning[0], self.tuning[1]
        return 1.0 / (LOAD_SCALE**2 * (dt / r_s + 2.0 / (q * dt)))

    def steady_state_covariance(self, dt: float, samples: int = 20000) -> np.ndarray:
        """Fixed point of the filter covariance recursion at interval ``dt``, inputs all valid."""
        step = self.filter._step
        P = self.filter.initial_state().P
        u = np.zeros(12)
        u[10] = 9.81
        valid = np.ones(12)
        for _ in range(samples):
            P_next = np.asarray(step(np.zeros(4), P, u, valid, dt, self.p, self.tuning)[1])
            if np.max(np.abs(P_next - P)) <= 1e-13 * np.max(np.abs(P)):
                return P_next
            P = P_next
        return P

    def log_terms(self, signals: Signals, fallback: Estimate, covariances: np.ndarray) -> LogTerms:
        """The QP data of every sample of ``signals`` (see :class:`LogTerms`)."""
        s = self.settings
        N, n = s.horizon, len(signals)
        dt = sample_intervals(signals.t)
        z, b = self.model_terms(signals)
        bits = np.array([flag.value for flag in StepFlag.update_flags()])
        used = (fallback.flags[:, None] & bits[None, :]) == 0
        q, r_s, r_c = self.tuning[0], self.tuning[1], self.tuning[2:5]
        w_s = used[:, :4] * (dt / r_s)[:, None]
        w_c = used[:, 4:] * dt[:, None] / r_c[None, :]
        w_q = 1.0 / (q * dt)
        P0 = self.filter.initial_state().P
        if s.arrival is Arrival.KALMAN:
            previous = np.concatenate([P0[None], covariances[:-1]])
            Pi = previous + (q * dt)[:, None, None] * np.eye(4)
        else:
            median = float(np.median(dt))
            steady = self.steady_state_covariance(median)
            Pi = np.broadcast_to(steady + q * median * np.eye(4), (n, 4, 4)).copy()
            Pi[0] = P0 + q * dt[0] * np.eye(4)
        Pi_inv = np.linalg.inv(Pi)
        Pi_inv = 0.5 * (Pi_inv + Pi_inv.transpose(0, 2, 1))
        w_q[0] = 0.0  # the first sample has no predecessor: the arrival cost takes its place
        cost = self.cost_factor(float(np.median(dt)))
        upper_load = s.max_load if s.bounded else math.inf
        lower_load = 0.0 if s.bounded else -math.inf
        if s.constraint is Constraint.SOFT:
            H = w_s[:, :, None] * np.eye(4) + np.einsum("ai,ka,aj->kij", self.A, w_c, self.A)
            g = -(w_s * z + (w_c * b) @ self.A)
            drift = np.zeros(n)
            lower = np.full((n, 4), lower_load)
            upper = np.full((n, 4), upper_load)
            xp = np.zeros((n, 4))
            inert_H = np.eye(4)
        else:
            xp = self._equilibrium_points(b, fallback.loads, used[:, 4:])
            nv = self.null
            H = (w_s * nv**2).sum(axis=1)
            g = nv @ (w_s * (xp - z)).T
            drift = w_q * (np.diff(xp, axis=0, prepend=xp[:1]) @ nv)
            lower, upper = self._warp_bounds(xp, lower_load, upper_load)
            inert_H = 1.0
        terms = dict(
            H=(cost * LOAD_SCALE**2 * H, inert_H),
            g=(cost * LOAD_SCALE * g, 0.0),
            drift=(cost * LOAD_SCALE * drift, 0.0),
            link=(cost * LOAD_SCALE**2 * w_q, 0.0),
            arrival=(cost * LOAD_SCALE**2 * Pi_inv, 0.0),
            lower=(lower / LOAD_SCALE, 0.0),
            upper=(upper / LOAD_SCALE, 0.0),
            particular=(xp, 0.0),
        )
        return LogTerms(**{key: _pad(value, N - 1, fill) for key, (value, fill) in terms.items()})

    def _equilibrium_points(self, b: np.ndarray, loads: np.ndarray, used: np.ndarray) -> np.ndarray:
        """:math:`A^+ b` per sample; a row with missing inputs takes ``A x`` of the filter."""
        b = np.where(used, b, loads @ self.A.T)
        return b @ self.pinv.T

    def _warp_bounds(
        self, xp: np.ndarray, lower_load: float, upper_load: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Interval of :math:`\\omega` with ``lower <= xp + n omega <= upper``, per sample.

        An empty interval (no bounded loads satisfy the equilibrium) collapses
        to its midpoint; the output is then clipped to the bounds.
        """
        nv = self.null
        with np.errstate(invalid="ignore"):
            a = (lower_load - xp) / nv
            c = (upper_load - xp) / nv
        low = np.where(nv > 0, a, c).max(axis=1)
        high = np.where(nv > 0, c, a).min(axis=1)
        empty = low > high
        with np.errstate(invalid="ignore"):
            middle = 0.5 * (low + high)
        low = np.where(empty, middle, low)
        high = np.where(empty, middle, high)
        return low, high

    # -- solving -----------------------------------------------------------------------------

    def run(self, signals: Signals) -> MheEstimate:
        """Estimate a whole log: one warm-started QP per sample, set up once."""
        fallback, covariances = self.filter.run_with_covariance(signals)
        terms = self.log_terms(signals, fallback, covariances)
        window = _Window(self, terms)
        n = len(signals)
        loads = np.empty((n, 4))
        status = np.empty(n, dtype=np.int64)
        iterations = np.empty(n, dtype=np.int64)
        failed = np.zeros(n, dtype=bool)
        seconds = np.empty(n)
        x0 = np.array(self.filter.parameters.static(), dtype=float)
        history = np.vstack([np.tile(x0, (self.settings.horizon, 1)), loads])
        for k in range(n):
            start = time.perf_counter()
            prior = history[k]
            x, status[k], iterations[k], ok = window.solve(k, prior)
            if not ok:
                x = np.clip(fallback.loads[k], *window.load_bounds)
                failed[k] = True
            loads[k] = x
            history[k + self.settings.horizon] = x
            seconds[k] = time.perf_counter() - start
        _, b = self.model_terms(signals)
        return MheEstimate(
            t=signals.t.copy(),
            loads=loads,
            std=fallback.std,
            residual=b - loads @ self.A.T,
            flags=fallback.flags,
            status=status,
            iterations=iterations,
            fallback=failed,
            solve_time=seconds,
        )


class _Window:
    """The OSQP problem of one window, set up once and updated per sample."""

    def __init__(self, mhe: MovingHorizonEstimator, terms: LogTerms) -> None:
        s = mhe.settings
        self.N = N = s.horizon
        self.hard = s.constraint is Constraint.HARD
        self.terms = terms
        self.null = mhe.null
        self.width = 1 if self.hard else 4
        self.load_bounds = (0.0, s.max_load) if s.bounded else (-math.inf, math.inf)
        self.bounded = s.bounded
        self.eps = (s.solver.eps_abs, s.solver.eps_rel)
        P = _hessian_pattern(N, self.width)
        self.order = _csc_value_order(N, self.width)
        P.data = self._hessian_values(0)
        self.last_Px = P.data.copy()
        q = self._linear(0, np.zeros(4))
        dimension = N * self.width
        if s.bounded:
            A = sp.identity(dimension, format="csc")
            l, u = self._bounds(0)
        else:
            A = sp.csc_matrix((0, dimension))
            l = u = np.zeros(0)
        self.solver = osqp.OSQP()
        self.solver.setup(
            P, q, A, l, u,
            verbose=False,
            eps_abs=s.solver.eps_abs,
            eps_rel=s.solver.eps_rel,
            max_iter=s.solver.max_iter,
            polishing=s.solver.polish,
            check_termination=s.solver.check_termination,
            adaptive_rho_interval=s.solver.adaptive_rho_interval,
            warm_starting=True,
        )  # fmt: skip
        self.x = np.zeros(dimension)
        self.y = np.zeros(A.shape[0])

    def _hessian_values(self, k: int) -> np.ndarray:
        t, N = self.terms, self.N
        window = slice(k, k + N)
        link = t.link[window]
        following = np.concatenate([link[1:], [0.0]])
        diagonal = link.copy()
        diagonal[0] = 0.0
        diagonal += following
        j0 = max(0, N - 1 - k)
        if self.hard:
            H = t.H[window] + diagonal
            H[j0] += self.null @ t.arrival[k + j0] @ self.null
            return np.concatenate([H, -link[1:]])[self.order]
        H = t.H[window] + diagonal[:, None, None] * np.eye(4)
        H[j0] += t.arrival[k + j0]
        off = np.repeat(-link[1:], 4)
        return np.concatenate([H.ravel(), off])[self.order]

    def _linear(self, k: int, prior: np.ndarray) -> np.ndarray:
        t, N = self.terms, self.N
        q = t.g[k : k + N].copy()
        j0 = max(0, N - 1 - k)
        W = t.arrival[k + j0]
        if self.hard:
            drift = t.drift[k + 1 : k + N]
            q[1:] += drift
            q[:-1] -= drift
            offset = (t.particular[k + j0] - prior) / LOAD_SCALE
            q[j0] += self.null @ W @ offset
        else:
            q[j0] -= W @ prior / LOAD_SCALE
        return q.ravel()

    def _bounds(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        t, N = self.terms, self.N
        return t.lower[k : k + N].ravel(), t.upper[k : k + N].ravel()

    def solve(self, k: int, prior: np.ndarray) -> tuple[np.ndarray, int, int, bool]:
        """Update the QP for the window ending at sample ``k`` and solve it."""
        solver = self.solver
        Px = self._hessian_values(k)
        if not np.array_equal(Px, self.last_Px):
            solver.update(Px=Px)
            self.last_Px = Px
        q = self._linear(k, prior)
        if self.bounded and (self.hard or k < self.N):
            l, u = self._bounds(k)  # the warm-up windows hold inert samples fixed at zero
            solver.update(q=q, l=l, u=u)
        else:
            solver.update(q=q)
        w = self.width
        self.x[:-w] = self.x[w:]
        if self.y.size:
            self.y[:-w] = self.y[w:]
            solver.warm_start(x=self.x, y=self.y)
        else:
            solver.warm_start(x=self.x)
        result = solver.solve(raise_error=False)
        status = int(result.info.status_val)
        iterations = int(result.info.iter)
        if status != SOLVED:
            return np.zeros(4), status, iterations, False
        self.x[:] = result.x
        if self.y.size:
            self.y[:] = result.y
        last = result.x[-w:]
        i = k + self.N - 1
        eps = self.eps
        clipped = _clip_checked(last, self.terms.lower[i], self.terms.upper[i], eps)
        if clipped is None:
            return np.zeros(4), status, iterations, False
        if self.hard:
            x = self.terms.particular[i] + self.null * (clipped[0] * LOAD_SCALE)
            # rounding of A^+ b + n omega only: far below a newton
            x = _clip_checked(x, *self.load_bounds, (1e-9, 1e-12))
            if x is None:
                return np.zeros(4), status, iterations, False
        else:
            x = clipped * LOAD_SCALE
        return x, status, iterations, True


def _clip_checked(value, low, high, eps: tuple[float, float]):
    r"""``value`` clipped to ``[low, high]``, or None if further out than the solver tolerance.

    The tolerance is ten times OSQP's primal one, :math:`\epsilon_{abs} +
    \epsilon_{rel} \max(1, \|value\|_\infty)`.
    """
    eps_abs, eps_rel = eps
    tolerance = 10.0 * (eps_abs + eps_rel * max(1.0, float(np.max(np.abs(value)))))
    if np.any(value < low - tolerance) or np.any(value > high + tolerance):
        return None
    return np.clip(value, low, high)


def _null_vector(A: np.ndarray) -> np.ndarray:
    """Unit vector spanning the null space of the rank-3 equilibrium matrix (the warp mode)."""
    _, singular, Vt = np.linalg.svd(A)
    if singular[-1] < 1e-9 * singular[0]:
        raise ValueError("equilibrium matrix A has rank below 3: check the vehicle geometry")
    nv = Vt[-1]
    return nv if nv[0] >= 0 else -nv


def _pad(value: np.ndarray, count: int, fill) -> np.ndarray:
    pad = np.broadcast_to(np.asarray(fill, dtype=float), (count, *value.shape[1:]))
    return np.concatenate([pad, value])


def _hessian_pattern(N: int, width: int) -> sp.csc_matrix:
    """Upper-triangular block-tridiagonal pattern: dense diagonal blocks, diagonal couplings."""
    rows, cols = [], []
    for j in range(N):
        for a in range(width):
            col = j * width + a
            if j > 0:
                rows.append(col - width)
                cols.append(col)
            for r in range(a + 1):
                rows.append(j * width + r)
                cols.append(col)
    n = N * width
    data = np.arange(1, len(rows) + 1, dtype=float)
    matrix = sp.csc_matrix((data, (rows, cols)), shape=(n, n))
    matrix.sort_indices()
    return matrix


def _csc_value_order(N: int, width: int) -> np.ndarray:
    """Indices into ``[diagonal blocks (N, w, w) raveled, couplings (N-1, w)]`` in CSC order."""
    index = []
    couplings = N * width * width
    for j in range(N):
        for a in range(width):
            if j > 0:
                index.append(couplings + (j - 1) * width + a)
            for r in range(a + 1):
                index.append(j * width * width + r * width + a)
    return np.array(index)
