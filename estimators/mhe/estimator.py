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

The per-sample terms come from one CasADi Function built from the model
Functions (:func:`wheelload.estimators.mhe.terms.terms_function`), mapped
over the log by :meth:`MovingHorizonEstimator.run` and called once per
sample by :meth:`MovingHorizonEstimator.step`; the generated C calls the
same Function. :class:`MheState` holds the window of terms, the fallback
filter's state, the previous estimates, the warm start and OSQP's
:math:`\rho`; ``step`` advances it. ``run`` advances the plain window
(quadratic losses, no bias states) in preallocated ring buffers instead
(:mod:`wheelload.estimators.mhe.ring`), with the same arithmetic and OSQP calls
as ``step``'s path, bit for bit; the extended window shares ``step``'s code. So
``run`` and ``step`` agree to rounding in the filter and the terms (far below
the solver tolerance).

The QP is set up once per estimator with a fixed sparsity; each sample
updates ``q`` (and ``l, u`` when they change), the Hessian values only when
they change (arrival weight, sample interval, missing inputs), warm-starts
with the shifted previous solution and solves. A sample whose QP is not solved
(status other than *solved*, or a bound violated by more than the solver
tolerance) takes the Kalman estimate, clipped to the bounds, and is marked
in :attr:`MheEstimate.fallback`. Bounds hold exactly: the solver's
violations, once checked to be within tolerance, are clipped.

A log's first sample (``state.k == 0``) sets the solver up afresh, so a run
is a function of its log and start state alone. A window in which no sample
has a data term (every input missing) is not solved: its minimiser is the
last estimate carried by the random walk, taken in closed form, so the
estimate is held without drift while the filter's :math:`\sigma` grows.

Example
-------
>>> mhe = MovingHorizonEstimator(vehicle, MheSettings(horizon=10, bounded=True))
>>> estimate = mhe.run(read_log("drive.csv"))
>>> state, one = mhe.step(mhe.initial_state(dt=0.01), sample, 0.01)
"""

from __future__ import annotations

import enum
import functools
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import osqp
import scipy.sparse as sp

from wheelload.estimators.kernels.validity import MAX_INTERVAL
from wheelload.estimators.kf.projection import ProjectionKF, Weighting
from wheelload.estimators.kf.two_stage import (
    FilterState,
    Sample,
    TwoStageKF,
    flags_from_used,
    sample_intervals,
)
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import Signals
from wheelload.estimators.mhe.quiet import quiet_stdout
from wheelload.estimators.mhe.ring import run_ring
from wheelload.estimators.mhe.terms import (
    LOAD_SCALE,
    Constraint,
    residual_function,
    terms_function,
)
from wheelload.estimators.mhe.window import (
    BiasStates,
    Loss,
    ResidualLoss,
    WindowQP,
    WindowSample,
    bias_scales,
    ride_height_basis,
    travel_basis,
)
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.models import GATES, GRAVITY, INPUTS, ModelParameters, Vehicle, equilibrium_function

__all__ = [
    "LOAD_SCALE",
    "Arrival",
    "BiasStates",
    "Constraint",
    "Loss",
    "ResidualLoss",
    "MheEstimate",
    "MheSettings",
    "MheState",
    "MovingHorizonEstimator",
    "SolverSettings",
]

SOLVED = osqp.SolverStatus.OSQP_SOLVED.value
#: Status of a sample whose QP data are not finite: not handed to OSQP, the filter's estimate.
UNSOLVED = osqp.SolverStatus.OSQP_UNSOLVED.value
#: Largest :math:`|F_z|` [m g] an estimate may take: a QP solution beyond it is not
#: solved (the filter's estimate), a filter estimate beyond it is not taken (the last
#: estimate is held). No road wheel carries twice the vehicle's weight.
LOAD_LIMIT = 2.0


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
    rho: float = 0.1  # initial ADMM step size; adapted during the solves and carried in the state

    def __post_init__(self) -> None:
        if not (self.eps_abs > 0 and self.eps_rel >= 0):
            raise ValueError(f"eps_abs must be > 0 and eps_rel >= 0, got {self}")
        if not self.rho > 0:
            raise ValueError(f"rho must be > 0, got {self.rho}")
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
    suspension_loss: ResidualLoss = field(default_factory=ResidualLoss)
    constraint_loss: ResidualLoss = field(default_factory=ResidualLoss)  # soft only
    bias_states: BiasStates = BiasStates.NONE
    lag: int = 0  # samples: the output is the window's estimate of sample k - lag

    def __post_init__(self) -> None:
        if not isinstance(self.horizon, int) or self.horizon < 1:
            raise ValueError(f"horizon must be an integer >= 1, got {self.horizon!r}")
        if not isinstance(self.constraint, Constraint):
            raise TypeError(f"constraint must be a Constraint, got {self.constraint!r}")
        if not isinstance(self.arrival, Arrival):
            raise TypeError(f"arrival must be an Arrival, got {self.arrival!r}")
        if not self.max_load > 0:
            raise ValueError(f"max_load must be > 0, got {self.max_load}")
        for name in ("suspension_loss", "constraint_loss"):
            if not isinstance(getattr(self, name), ResidualLoss):
                raise TypeError(f"{name} must be a ResidualLoss, got {getattr(self, name)!r}")
        if not isinstance(self.bias_states, BiasStates):
            raise TypeError(f"bias_states must be BiasStates, got {self.bias_states!r}")
        if not isinstance(self.lag, int) or not 0 <= self.lag < self.horizon:
            raise ValueError(f"lag must be an integer in [0, horizon), got {self.lag!r}")
        hard = self.constraint is Constraint.HARD
        both = (
            BiasStates.TRAVEL | BiasStates.RIDE_HEIGHT,
            BiasStates.ACCELERATION | BiasStates.LATERAL,
        )
        if any(pair in self.bias_states for pair in both):
            raise ValueError(
                "bias_states: TRAVEL and RIDE_HEIGHT exclude each other, as do ACCELERATION "
                "and LATERAL"
            )
        if hard and self.bias_states.acceleration_columns:
            raise ValueError(
                "acceleration bias states need the soft constraint (hard: the bounds would "
                "move with the bias); use constraint=Constraint.SOFT"
            )
        if hard and self.constraint_loss.robust:
            raise ValueError("a hard constraint has no residual: constraint_loss must be quadratic")

    @property
    def extended(self) -> bool:
        """True when the window needs auxiliary or bias variables (:mod:`mhe_window`)."""
        return (
            self.suspension_loss.robust
            or self.constraint_loss.robust
            or self.bias_states != BiasStates.NONE
        )

    def label(self) -> str:
        bounds = ", bounded" if self.bounded else ""
        arrival = ", steady arrival" if self.arrival is Arrival.STEADY_STATE else ""
        extra = ""
        if self.suspension_loss.robust:
            extra += f", susp {self.suspension_loss.label()}"
        if self.constraint_loss.robust:
            extra += f", eq {self.constraint_loss.label()}"
        if self.bias_states != BiasStates.NONE:
            extra += f", {self.bias_states.label()}"
        if self.lag:
            extra += f", lag {self.lag}"
        return f"MHE N={self.horizon} ({self.constraint.value}{bounds}{arrival}{extra})"


@dataclass(frozen=True, kw_only=True, eq=False)
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
    terms, bounds 0). Terms are in the QP's units (see :mod:`mhe_terms`).
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
class _SampleTerms:
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
        s = self.settings
        self.hard = s.constraint is Constraint.HARD
        self.filter = (
            ProjectionKF(vehicle, weighting=Weighting.MAXIMUM_PROBABILITY, static=static)
            if self.hard
            else TwoStageKF(vehicle, static=static)
        )
        self.p = self.filter.p
        self.tuning = self.filter.tuning
        A, _ = equilibrium_function()(np.zeros(len(INPUTS)), np.zeros(len(GATES)), self.p)
        self.A = np.asarray(A)
        self.null = _null_vector(self.A)
        self.pinv = np.linalg.pinv(self.A)
        self.width = 1 if self.hard else 4
        self.load_bounds = (0.0, s.max_load) if s.bounded else (-math.inf, math.inf)
        mass = float(self.p[ModelParameters.names().index("mass")])
        #: N, :data:`LOAD_LIMIT` times the vehicle's weight
        self.load_limit = LOAD_LIMIT * mass * GRAVITY
        self.terms = terms_function(
            s.constraint,
            null=self.null,
            pinv=self.pinv,
            lower_load=self.load_bounds[0],
            upper_load=self.load_bounds[1],
        )
        self.workspace = _Workspace(s, self.width)
        if s.extended:
            std, self.beta_bound, self.beta_density = bias_scales(s.bias_states, vehicle)
            nd = s.bias_states.travel_states
            self.residuals = residual_function()
            u0 = np.zeros(len(INPUTS))
            Jd = np.asarray(self.residuals(u0, np.ones(len(INPUTS)), 0.01, self.p, self.tuning)[1])
            self.travel_basis = (
                travel_basis(Jd, self.null)
                if BiasStates.TRAVEL in s.bias_states
                else ride_height_basis()
            )
            self.acceleration_columns = s.bias_states.acceleration_columns
            self.beta_std = std
            self.window_qp = WindowQP(
                horizon=s.horizon, hard=self.hard, A=self.A, null=self.null,
                suspension=s.suspension_loss, constraint=s.constraint_loss,
                n_bias=std.size, travel_basis=self.travel_basis if nd else None,
                solver=s.solver,
            )  # fmt: skip

    # -- set-up ------------------------------------------------------------------------------

    def cost_factor(self, dt: float) -> float:
        """Cost scale :math:`c`: the QP's Hessian :math:`c s^2 H` has diagonal entries near one."""
        q, r_s = self.tuning[0], self.tuning[1]
        return 1.0 / (LOAD_SCALE**2 * (dt / r_s + 2.0 / (q * dt)))

    def steady_state_covariance(self, dt: float, samples: int = 20000) -> np.ndarray:
        """Fixed point of the filter covariance recursion at interval ``dt``, inputs all valid."""
        step = self.filter._step
        P = self.filter.initial_state().P
        u = np.zeros(len(INPUTS))
        u[INPUTS.index("az")] = 9.81
        valid = np.ones(len(INPUTS))
        for _ in range(samples):
            P_next = np.asarray(step(np.zeros(4), P, u, valid, dt, self.p, self.tuning)[1])
            if np.max(np.abs(P_next - P)) <= 1e-13 * np.max(np.abs(P)):
                return P_next
            P = P_next
        return P

    def initial_state(self, dt: float) -> MheState:
        """A window of inert samples before the log; ``dt`` [s] is the nominal sample interval.

        ``dt`` sets the cost scale and, with :attr:`Arrival.STEADY_STATE`,
        the interval of the steady-state arrival weight. :meth:`run` takes
        the median interval of its log.
        """
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"the nominal sample interval must be > 0, got {dt}")
        N, w = self.settings.horizon, self.width
        cost = self.cost_factor(dt)
        if self.settings.arrival is Arrival.STEADY_STATE:
            steady = self.steady_state_covariance(dt)
            steady = _arrival_weights(steady[None], self.tuning[0] * np.array([dt]), cost)[0]
        else:
            steady = np.zeros((4, 4))
        x0 = np.array(self.filter.parameters.static(), dtype=float)
        state = MheState(
            k=0,
            cost=cost,
            steady=steady,
            kf=self.filter.initial_state(),
            H=np.broadcast_to(np.eye(w), (N, w, w)).copy(),
            g=np.zeros((N, w)),
            link=np.zeros(N),
            drift=np.zeros(N),
            xp=np.zeros((N, 4)),
            lower=np.zeros((N, w)),
            upper=np.zeros((N, w)),
            arrival=np.zeros((N, 4, 4)),
            history=np.tile(x0, (N, 1)),
            x=np.zeros(N * w),
            y=np.zeros(N * w if self.settings.bounded else 0),
            rho=self.settings.solver.rho,
            kfx=np.tile(x0, (N, 1)),
        )
        if self.settings.extended:
            state = replace(state, **self._initial_extended(x0))
        return state

    def _initial_extended(self, x0: np.ndarray) -> dict:
        """The extended window's inert samples, warm start and bias prior."""
        qp, w = self.window_qp, self.width
        inert = WindowSample(
            z=x0, Jd=np.zeros((4, 4)), b=np.zeros(3),
            Ba=np.zeros((3, len(self.acceleration_columns))), ls=np.zeros(4),
            lc=np.zeros(3), xp=np.zeros(4), link=0.0, lower=np.zeros(w), upper=np.zeros(w),
        )  # fmt: skip
        return dict(
            samples=(inert,) * self.settings.horizon,
            local=(qp.local_terms(inert),) * self.settings.horizon,
            x=np.zeros(qp.n),
            y=np.zeros(qp.n),
            beta=np.zeros(self.beta_std.size),
            beta_info=np.diag(1.0 / self.beta_std**2),
        )

    # -- per sample --------------------------------------------------------------------------

    def step(self, state: MheState, sample: Sample, dt: float) -> tuple[MheState, MheEstimate]:
        """Filter one sample, add its terms to the window and solve; returns the new state.

        Same numbers as :meth:`run` over the same samples from the same state. A
        non-positive or non-finite ``dt`` solves nothing: the state and the last
        estimate are held and flagged ``STEP_REJECTED`` (status 0).
        """
        if not 0.0 < dt < MAX_INTERVAL:
            return state, self._rejected(state, sample, dt)
        u = sample.vector()
        valid = np.isfinite(u).astype(float)
        kf, estimate = self.filter.step(state.kf, sample, dt)
        out = self.terms(
            np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0),
            valid, dt, kf.x, self.p, self.tuning, state.cost,
        )  # fmt: skip
        H, g, link, xp, lower, upper, b, used = (np.asarray(o).ravel() for o in out)
        rows = None
        if self.settings.extended:
            rows = tuple(
                np.asarray(o)
                for o in self.residuals(np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0),
                                        valid, dt, self.p, self.tuning)
            )  # fmt: skip
            rows = (rows[0].ravel(), rows[1], rows[2], rows[3].ravel(), rows[4].ravel())
        terms = _SampleTerms(
            H, g, float(link[0]), xp, lower, upper, b, used, kf, estimate.std[0], rows
        )
        arrival = self._arrival(state, state.kf.P[None], np.array([dt]))[0]
        state, report = self._advance(state, terms, arrival)
        return state, _estimate(np.array([np.nan]), [report], self.A, lag=self.settings.lag)

    def _rejected(self, state: MheState, sample: Sample, dt: float) -> MheEstimate:
        """The held estimate of a sample whose interval is rejected."""
        kf, held_kf = self.filter.step(state.kf, sample, dt)
        held = state.history[-1]
        return MheEstimate(
            t=np.array([np.nan]),
            loads=held[None, :],
            std=held_kf.std,
            residual=held_kf.residual + ((kf.x - held) @ self.A.T)[None, :],
            flags=held_kf.flags,
            status=np.zeros(1, dtype=np.int64),
            iterations=np.zeros(1, dtype=np.int64),
            fallback=np.zeros(1, dtype=bool),
            solve_time=np.zeros(1),
        )

    def _arrival(self, state: MheState, previous: np.ndarray, dt: np.ndarray) -> np.ndarray:
        r"""Arrival weights :math:`c s^2 \Pi^{-1}` of samples ``state.k, state.k + 1, ...``.

        ``previous`` holds the filter covariance before each sample.
        """
        weights = _arrival_weights(previous, self.tuning[0] * dt, state.cost)
        if self.settings.arrival is Arrival.STEADY_STATE:
            first = np.arange(len(dt)) + state.k == 0  # the log's first sample: P0 + Q
            weights = np.where(first[:, None, None], weights, state.steady)
        return weights

    def _advance(self, state: MheState, terms: _SampleTerms, arrival: np.ndarray):
        """Push one sample's terms into the window, solve, and return the state and report."""
        if self.settings.extended:
            return self._advance_extended(state, terms, arrival)
        start = time.perf_counter()
        link = terms.link if state.k > 0 else 0.0  # the log's first sample: the arrival instead
        drift = link / LOAD_SCALE * float(self.null @ (terms.xp - state.xp[-1]))
        w = self.width
        window = dict(
            H=_shift(state.H, terms.H.reshape(w, w)),
            g=_shift(state.g, terms.g),
            link=_shift(state.link, link),
            drift=_shift(state.drift, drift if self.hard else 0.0),
            xp=_shift(state.xp, terms.xp),
            lower=_shift(state.lower, terms.lower),
            upper=_shift(state.upper, terms.upper),
            arrival=_shift(state.arrival, arrival),
        )
        N = self.settings.horizon
        j0 = max(0, N - 1 - state.k)
        prior = state.history[0]
        if state.k == 0:  # a new log: a fresh solver, so a run depends on its log alone
            self.workspace = _Workspace(self.settings, self.width)
        x_warm = np.concatenate([state.x[w:], state.x[-w:]])
        y_warm = np.concatenate([state.y[w:], state.y[-w:]]) if state.y.size else state.y
        rho = state.rho
        x = None
        if not np.any(window["H"][j0:]):
            # No sample in the window has a data term: the minimiser is the prior carried by
            # the random walk, in closed form (the QP is ill-conditioned there). Without data
            # since sample k-N, the last estimate is that prior carried forward (equal in exact
            # arithmetic) and is taken, so no solver rounding cycles with period N.
            last = state.history[-1]
            x_warm = _prior_solution(window, j0, last, self.null, self.hard, x_warm, w)
            status, iterations = SOLVED, 0
            x = self._loads(x_warm[-w:], window)
        else:
            Px = _hessian_values(window, j0, self.null, self.hard)
            q = _linear(window, j0, prior, self.null, self.hard)
            bounds = (window["lower"].ravel(), window["upper"].ravel()) if state.y.size else None
            if finite_data(Px, q, *(bounds or ())):
                result, rho = self.workspace.solve(Px, q, bounds, x_warm, y_warm, state.rho)
                status, iterations = int(result.info.status_val), int(result.info.iter)
            else:
                status, iterations = UNSOLVED, 0
            if status == SOLVED:
                x_warm, y_warm = np.array(result.x), np.array(result.y)
                x = self._loads(x_warm[-w:], window)
        failed = x is None
        if failed:
            x = self.fallback_loads(terms.kf.x, state.history[-1])
        kfx = _shift(state.kfx, terms.kf.x)
        state = replace(
            state,
            k=state.k + 1,
            kf=terms.kf,
            history=_shift(state.history, x),
            x=x_warm,
            y=y_warm,
            rho=rho,
            kfx=kfx,
            **window,
        )
        lagged = (
            x
            if self.settings.lag == 0 or failed
            else self.window_loads(state, N - 1 - self.settings.lag)
        )
        report = (lagged, terms, status, iterations, failed, time.perf_counter() - start, None)
        return state, report

    def window_loads(self, state: MheState, j: int) -> np.ndarray:
        """The loads [N] of window sample ``j`` (0 oldest) in the state's last solution.

        A value outside its bounds by more than the tolerance gives the
        filter's estimate of that sample, clipped.
        """
        if self.settings.extended:
            qp = self.window_qp
            block = state.x[qp.y(j)]
            sample = state.samples[j]
            x = self._checked(block, sample.lower, sample.upper, sample.xp)
        else:
            w = self.width
            block = state.x[j * w : (j + 1) * w]
            x = self._checked(block, state.lower[j], state.upper[j], state.xp[j])
        return self.fallback_loads(state.kfx[j], state.history[-1]) if x is None else x

    def fallback_loads(self, filtered: np.ndarray, held: np.ndarray) -> np.ndarray:
        """The loads of a sample whose QP is not solved: the filter's, clipped to the bounds.

        A filter estimate that is not finite or beyond :attr:`load_limit` is not
        taken: ``held`` (the last estimate) is, so no output is ever non-finite.
        """
        source = filtered if self.plausible_loads(filtered) else held
        return np.clip(source, *self.load_bounds)

    def plausible_loads(self, x) -> bool:
        """True when every load is finite and within :attr:`load_limit` (NaN fails)."""
        limit = self.load_limit
        return all(abs(value) <= limit for value in np.asarray(x, dtype=float).tolist())

    def _checked(self, block, lower, upper, xp) -> np.ndarray | None:
        r"""Loads [N] from one sample's QP variables, or None if out of bounds.

        Hard constraint: a collapsed warp interval (``lower == upper``, no bounded loads
        satisfy the equilibrium, :func:`~wheelload.estimators.mhe.terms.warp_interval`)
        gives :math:`A^+ b + n\,\omega` at its midpoint clipped to the bounds, a solved
        sample; elsewhere the loads must lie within the bounds up to rounding.
        """
        eps = (self.settings.solver.eps_abs, self.settings.solver.eps_rel)
        clipped = _clip_checked(block, lower, upper, eps)
        if clipped is None:
            return None
        if not self.hard:
            x = clipped * LOAD_SCALE
        else:
            x = xp + self.null * (clipped[0] * LOAD_SCALE)
            if float(lower[0]) == float(upper[0]):
                x = np.clip(x, *self.load_bounds)
            else:
                x = _clip_checked(x, *self.load_bounds, (1e-9, 1e-12))
        return x if x is not None and self.plausible_loads(x) else None

    def _advance_extended(self, state: MheState, terms: _SampleTerms, arrival: np.ndarray):
        """:meth:`_advance` for the window with robust losses and bias states."""
        start = time.perf_counter()
        qp, N, w, c = self.window_qp, self.settings.horizon, self.width, state.cost
        z, Jd, Ba, ls, lc = terms.rows
        link = terms.link if state.k > 0 else 0.0
        sample = WindowSample(
            z=z, Jd=Jd, b=terms.b, Ba=Ba[:, self.acceleration_columns], ls=ls, lc=lc, xp=terms.xp,
            link=link / (c * LOAD_SCALE**2), lower=terms.lower, upper=terms.upper,
        )  # fmt: skip
        samples = state.samples[1:] + (sample,)
        local = state.local[1:] + (qp.local_terms(sample),)
        arrivals = _shift(state.arrival, arrival)
        kfx = _shift(state.kfx, terms.kf.x)
        j0 = max(0, N - 1 - state.k)
        if state.k == 0:
            qp.setup()
        width = qp.width
        shifted = np.concatenate([state.x[width : N * width], state.x[(N - 1) * width : N * width]])
        x_warm = np.concatenate([shifted, state.x[N * width :]])
        shifted = np.concatenate([state.y[width : N * width], state.y[(N - 1) * width : N * width]])
        y_warm = np.concatenate([shifted, state.y[N * width :]])
        beta, info = state.beta, state.beta_info
        x = None
        if not any(np.any(s.ls) or np.any(s.lc) for s in samples[j0:]):
            # no data in the window: hold, as in the plain window (see _advance)
            loads = x_warm[: N * width].reshape(N, width)[:, :w].ravel()
            window = dict(arrival=arrivals, xp=np.array([s.xp for s in samples]),
                          lower=np.array([s.lower for s in samples]),
                          upper=np.array([s.upper for s in samples]))  # fmt: skip
            loads = _prior_solution(window, j0, state.history[-1], self.null, self.hard, loads, w)
            blocks = x_warm[: N * width].reshape(N, width).copy()
            blocks[:, :w] = loads.reshape(N, w)
            blocks[:, w:] = 0.0
            x_warm = np.concatenate([blocks.ravel(), beta])
            status, iterations = SOLVED, 0
        else:
            Px, g = qp.assemble_values(
                samples,
                j0,
                state.history[0],
                arrivals[j0] / (c * LOAD_SCALE**2),
                beta,
                info,
                local,
                c,
            )
            low, high = qp.bounds(samples, j0, self.beta_bound)  # fmt: skip
            if finite_data(Px, g, low, high):
                status, iterations, x_new, y_new = qp.solve_raw(Px, g, low, high, x_warm, y_warm)
            else:
                status, iterations = UNSOLVED, 0
            if status == SOLVED:
                x_warm, y_warm = np.array(x_new), np.array(y_new)
        state = replace(state, samples=samples, local=local, x=x_warm, y=y_warm, kfx=kfx)
        if status == SOLVED:
            x = self._checked(x_warm[qp.y(N - 1)], sample.lower, sample.upper, sample.xp)
        failed = x is None
        if failed:
            x = self.fallback_loads(terms.kf.x, state.history[-1])
        else:
            beta = np.clip(x_warm[qp.beta], -self.beta_bound, self.beta_bound)
            if state.k >= N - 1 and beta.size:  # the oldest sample leaves the window next
                info = info + self._leaving_information(state, x_warm)
        if beta.size:
            dt = 1.0 / (self.tuning[0] * max(sample.link, 1e-300)) if sample.link else 0.0
            info = np.linalg.inv(np.linalg.inv(info) + np.diag(self.beta_density * dt))
        state = replace(
            state,
            k=state.k + 1,
            kf=terms.kf,
            history=_shift(state.history, x),
            rho=state.rho,
            arrival=arrivals,
            beta=beta,
            beta_info=0.5 * (info + info.T),
        )
        lag = self.settings.lag
        lagged = x if lag == 0 or failed else self.window_loads(state, N - 1 - lag)
        report = (lagged, terms, status, iterations, failed, time.perf_counter() - start,
                  self.bias_report(beta))  # fmt: skip
        return state, report

    def bias_report(self, beta: np.ndarray) -> np.ndarray:
        """Bias states in reporting units: travel offsets FL..RR [m], then ax, ay [m/s^2]."""
        nd = self.settings.bias_states.travel_states
        if not nd:
            return beta
        offsets = self.travel_basis @ beta[:nd] * 1e-3
        return np.concatenate([offsets, beta[nd:]])

    def _leaving_information(self, state: MheState, v: np.ndarray) -> np.ndarray:
        """Bias information of the window's oldest sample at the solution ``v``."""
        qp = self.window_qp
        s = state.samples[0]
        y = v[qp.y(0)]
        beta = v[qp.beta]
        x = s.xp + qp.X @ y
        nd = qp.travel_basis.shape[1]
        delta = qp.travel_basis @ beta[:nd] * 1e-3 if nd else np.zeros(4)
        beta_a = beta[nd:]
        rho_s = s.ls * (s.z - (s.Jd @ delta) - x)
        rho_c = s.lc * (s.b - s.Ba @ beta_a - self.A @ x)
        return qp.bias_information(s, rho_s, rho_c)

    def _loads(self, last: np.ndarray, window: dict) -> np.ndarray | None:
        """The newest sample's loads [N] from its QP variables, or None (:meth:`_checked`)."""
        return self._checked(last, window["lower"][-1], window["upper"][-1], window["xp"][-1])

    # -- whole log ---------------------------------------------------------------------------

    def run(self, signals: Signals, state: MheState | None = None) -> MheEstimate:
        """Estimate a whole log; the same numbers as :meth:`step` over its samples.

        The filter runs in compiled code and the terms Function is mapped
        over the log first; each sample then goes through the window update
        and solve of :meth:`step` (the plain window: the same arithmetic in ring
        buffers, :mod:`~wheelload.estimators.mhe.ring`). Without ``state`` the
        window starts from :meth:`initial_state` at the median interval.
        """
        n = len(signals)
        dt = sample_intervals(signals.t)
        state = state or self.initial_state(float(np.median(dt)))
        fallback, covariances = self.filter.run_with_covariance(signals, state.kf)
        u = input_matrix(signals)
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        out = self.terms.map(n)(
            u, valid, dt[None], fallback.loads.T, self.p, self.tuning, state.cost
        )
        H, g, link, xp, lower, upper, b, used = (np.asarray(o).T for o in out)
        rows = [None] * n
        if self.settings.extended:
            z, Jd, Ba, ls, lc = (np.asarray(o) for o in self.residuals.map(n)(
                u, valid, dt[None], self.p, self.tuning))  # fmt: skip
            rows = [
                (z[:, k], Jd[:, 4 * k : 4 * k + 4], Ba[:, 2 * k : 2 * k + 2], ls[:, k], lc[:, k])
                for k in range(n)
            ]
        previous = np.concatenate([state.kf.P[None], covariances[:-1]])
        arrival = self._arrival(state, previous, dt)
        if not self.settings.extended and not self._per_sample_states:
            return self._run_ring(signals, state, (H, g, link, xp, lower, upper, b, used),
                                  fallback, arrival)  # fmt: skip
        reports = []
        for k in range(n):
            kf = FilterState(fallback.loads[k], covariances[k])
            terms = _SampleTerms(
                H[k], g[k], float(link[k, 0]), xp[k], lower[k], upper[k], b[k], used[k], kf,
                fallback.std[k], rows[k],
            )  # fmt: skip
            state, report = self._advance(state, terms, arrival[k])
            reports.append(report)
        lag = self.settings.lag
        if lag:  # row i: the estimate of sample i; the log's last samples from its last window
            N = self.settings.horizon
            tail = [self.window_loads(state, N - lag + m) for m in range(min(lag, n))]
            lagged = [r[0] for r in reports[lag:]] + tail[max(0, lag - n) :]
            reports = [(x, *r[1:]) for x, r in zip(lagged, reports)]
        return _estimate(signals.t.copy(), reports, self.A, lag=lag)

    #: True: :meth:`run` advances the plain window through :meth:`_advance` and a new
    #: :class:`MheState` per sample (the reference the ring buffers are tested against)
    _per_sample_states = False
    #: a list: the ring loop appends each solved QP's data to it (``wheelload bench mhe``)
    _qp_record: list | None = None

    def _run_ring(self, signals: Signals, state: MheState, out: tuple, fallback, arrival):
        """The plain window's loop in preallocated ring buffers (:mod:`mhe_ring`)."""
        H, g, link, xp, lower, upper, b, used = out
        loads, status, iterations, failed, solve_time, final = run_ring(
            self, state, H, g, link, xp, lower, upper, fallback.loads, arrival, self._qp_record
        )
        n, lag, N = len(signals), self.settings.lag, self.settings.horizon
        if lag:  # row i: the estimate of sample i; the log's last samples from its last window
            tail = [final(N - lag + m) for m in range(min(lag, n))]
            loads = np.vstack([loads[lag:], np.array(tail[max(0, lag - n) :]).reshape(-1, 4)])
        return MheEstimate(
            t=signals.t.copy(),
            loads=loads,
            std=fallback.std.reshape(-1, 4),
            residual=b.reshape(-1, 3) - loads @ self.A.T,
            flags=flags_from_used(used.reshape(-1, len(StepFlag.update_flags())).T),
            status=status,
            iterations=iterations,
            fallback=failed,
            solve_time=solve_time,
            lag=lag,
            bias=None,
        )


def _estimate(t: np.ndarray, reports: list, A: np.ndarray, lag: int = 0) -> MheEstimate:
    """The :class:`MheEstimate` of the reports of :meth:`MovingHorizonEstimator._advance`."""
    loads = np.array([r[0] for r in reports]).reshape(-1, 4)
    terms = [r[1] for r in reports]
    bias = None if reports[0][6] is None else np.array([r[6] for r in reports])
    b = np.array([s.b for s in terms]).reshape(-1, 3)
    used = np.array([s.used for s in terms]).reshape(-1, len(StepFlag.update_flags()))
    return MheEstimate(
        t=t,
        loads=loads,
        std=np.array([s.std for s in terms]).reshape(-1, 4),
        residual=b - loads @ A.T,
        flags=flags_from_used(used.T),
        status=np.array([r[2] for r in reports], dtype=np.int64),
        iterations=np.array([r[3] for r in reports], dtype=np.int64),
        fallback=np.array([r[4] for r in reports], dtype=bool),
        solve_time=np.array([r[5] for r in reports], dtype=float),
        lag=lag,
        bias=bias,
    )


def _arrival_weights(P: np.ndarray, q_dt: np.ndarray, cost: float) -> np.ndarray:
    r""":math:`c s^2 (P + q\,dt\,I)^{-1}`, symmetrised, for each of the stacked ``P``."""
    W = np.linalg.inv(P + q_dt[:, None, None] * np.eye(4))
    return cost * LOAD_SCALE**2 * 0.5 * (W + W.transpose(0, 2, 1))


def _prior_solution(
    window: dict, j0: int, prior: np.ndarray, null: np.ndarray, hard: bool, x: np.ndarray, w: int
) -> np.ndarray:
    r"""The window's minimiser when no sample has a data term: the prior, carried unchanged.

    Soft: :math:`x_j = \bar x` for every sample from :math:`j_0`. Hard:
    :math:`\omega_{j_0} = n^\top \Pi^{-1}(\bar x - \bar x_{j_0}) / n^\top \Pi^{-1} n`,
    then the random walk's increments in the warp direction are zero:
    :math:`\omega_j = \omega_{j-1} - n^\top(\bar x_j - \bar x_{j-1})`. Each is clipped
    to its bounds (interval ends) afterwards. Samples before :math:`j_0` keep the warm start
    ``x``.
    """
    solution = x.copy().reshape(-1, w)
    if hard:
        W = window["arrival"][j0]
        xp = window["xp"]
        omega = float(null @ W @ (prior - xp[j0]) / (null @ W @ null)) / LOAD_SCALE
        for j in range(j0, len(xp)):
            if j > j0:
                omega -= float(null @ (xp[j] - xp[j - 1])) / LOAD_SCALE
            solution[j, 0] = omega
    else:
        solution[j0:] = prior / LOAD_SCALE
    solution[j0:] = np.clip(solution[j0:], window["lower"][j0:], window["upper"][j0:])
    return solution.ravel()


def _shift(window: np.ndarray, newest) -> np.ndarray:
    """``window`` moved one sample on, ``newest`` appended at the end."""
    return np.concatenate([window[1:], np.asarray(newest, dtype=float)[None]])


def _hessian_values(window: dict, j0: int, null: np.ndarray, hard: bool) -> np.ndarray:
    """Values of the window's upper-triangular Hessian in CSC order (:func:`_csc_value_order`)."""
    link = window["link"]
    N = link.size
    diagonal = link.copy()
    diagonal[0] = 0.0
    diagonal[:-1] += link[1:]
    arrival = window["arrival"][j0]
    if hard:
        H = window["H"][:, 0, 0] + diagonal
        H[j0] += null @ arrival @ null
        values = np.concatenate([H, -link[1:]])
    else:
        H = window["H"] + diagonal[:, None, None] * np.eye(4)
        H[j0] += arrival
        values = np.concatenate([H.ravel(), np.repeat(-link[1:], 4)])
    return values[_csc_value_order(N, 1 if hard else 4)]


def _linear(window: dict, j0: int, prior: np.ndarray, null: np.ndarray, hard: bool) -> np.ndarray:
    """The window's linear term ``q``: samples' terms, random-walk drift, arrival prior."""
    q = window["g"].copy()
    W = window["arrival"][j0]
    if hard:
        drift = window["drift"][1:]
        q[1:, 0] += drift
        q[:-1, 0] -= drift
        q[j0, 0] += null @ W @ (window["xp"][j0] - prior) / LOAD_SCALE
    else:
        q[j0] -= W @ prior / LOAD_SCALE
    return q.ravel()


class _Workspace:
    """The window's OSQP problem, set up once with placeholder values and updated per sample.

    It remembers the values it holds (Hessian, bounds, :math:`\\rho`) and
    updates only what differs, so a state from elsewhere gives the same
    numbers as the one it continued from.
    """

    def __init__(self, settings: MheSettings, width: int) -> None:
        N = settings.horizon
        dimension = N * width
        P = _hessian_pattern(N, width)
        placeholder = np.concatenate(
            [np.eye(width).ravel()] * N + [np.full((N - 1) * width, -0.25)]
        )
        P.data = placeholder[_csc_value_order(N, width)]
        self.Px = P.data.copy()
        if settings.bounded:
            A = sp.identity(dimension, format="csc")
            self.bounds = (np.zeros(dimension), np.zeros(dimension))
        else:
            A = sp.csc_matrix((0, dimension))
            self.bounds = (np.zeros(0), np.zeros(0))
        self.rho = settings.solver.rho
        # polishing needs inequality constraints (an active set); without them it only prints
        self.polish = settings.solver.polish and settings.bounded
        self.solver = osqp.OSQP()
        self.solver.setup(
            P, np.zeros(dimension), A, *self.bounds,
            verbose=False,
            eps_abs=settings.solver.eps_abs,
            eps_rel=settings.solver.eps_rel,
            max_iter=settings.solver.max_iter,
            polishing=self.polish,
            check_termination=settings.solver.check_termination,
            adaptive_rho_interval=settings.solver.adaptive_rho_interval,
            rho=self.rho,
            warm_starting=True,
        )  # fmt: skip

    def solve(self, Px, q, bounds, x, y, rho):
        """Load what changed, warm-start with ``x, y`` and solve; returns (result, rho)."""
        solver = self.solver
        if not np.array_equal(Px, self.Px):
            solver.update(Px=Px)
            self.Px = Px
        if rho != self.rho:
            solver.update_settings(rho=rho)
        if bounds is not None and not (
            np.array_equal(bounds[0], self.bounds[0]) and np.array_equal(bounds[1], self.bounds[1])
        ):
            solver.update(q=q, l=bounds[0], u=bounds[1])
            self.bounds = bounds
        else:
            solver.update(q=q)
        solver.warm_start(x=x, y=y if y.size else None)
        if self.polish:
            with quiet_stdout():
                result = solver.solve(raise_error=False)
        else:
            result = solver.solve(raise_error=False)
        self.rho = solver._solver.get_settings().rho  # adapted during the solve
        return result, self.rho


def finite_data(*arrays) -> bool:
    """True when no entry is NaN and none but a bound is infinite.

    The Hessian values and the linear term must be finite; bounds may be
    :math:`\\pm\\infty` (OSQP's "no bound") but not NaN. One reduction per array:
    a NaN, or both infinities, make the sum NaN; an infinity in the first two, or an
    overflow of their sum, makes it infinite.
    """
    Px, q, *bounds = arrays
    if not math.isfinite(float(Px.sum()) + float(q.sum())):
        return False
    for b in bounds:
        if math.isnan(float(b.sum())):
            return False
    return True


def _clip_checked(value, low, high, eps: tuple[float, float]):
    r"""``value`` clipped to ``[low, high]``, or None if further out than the solver tolerance.

    The tolerance is ten times OSQP's primal one, :math:`\epsilon_{abs} +
    \epsilon_{rel} \max(1, \|value\|_\infty)`.
    """
    eps_abs, eps_rel = eps
    # one to four entries: plain floats, no numpy reductions (same values as np.clip)
    v = value.tolist()
    lows = low.tolist() if isinstance(low, np.ndarray) else [float(low)] * len(v)
    highs = high.tolist() if isinstance(high, np.ndarray) else [float(high)] * len(v)
    tolerance = 10.0 * (eps_abs + eps_rel * max(1.0, max(map(abs, v))))
    clipped = []
    for x, a, b in zip(v, lows, highs):
        if x < a - tolerance or x > b + tolerance:
            return None
        clipped.append(min(max(x, a), b))
    return np.array(clipped)


def _null_vector(A: np.ndarray) -> np.ndarray:
    """Unit vector spanning the null space of the rank-3 equilibrium matrix (the warp mode)."""
    _, singular, Vt = np.linalg.svd(A)
    if singular[-1] < 1e-9 * singular[0]:
        raise ValueError("equilibrium matrix A has rank below 3: check the vehicle geometry")
    nv = Vt[-1]
    return nv if nv[0] >= 0 else -nv


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


@functools.cache
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
