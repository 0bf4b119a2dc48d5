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
(quadratic losses, no bias states) in whole-log arrays instead
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

import math
import time
from dataclasses import replace

import numpy as np

from wheelload.estimators.guards.limits import variance_ceiling
from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.kf.projection import ProjectionKF, Weighting
from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.kf.two_stage import (
    FilterState,
    TwoStageKF,
)
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.mhe.extended import advance_extended, initial_extended
from wheelload.estimators.mhe.qp import (
    LOAD_LIMIT,
    SOLVED,
    UNSOLVED,
    LoadCheck,
    MheWorkspace,
    arrival_weights,
    finite_data,
    hessian_values,
    linear_term,
    null_vector,
    prior_solution,
)
from wheelload.estimators.mhe.ring import run_ring
from wheelload.estimators.mhe.settings import (
    Arrival,
    BiasStates,
    Constraint,
    MheSettings,
)
from wheelload.estimators.mhe.state import (
    MheEstimate,
    MheState,
    SampleTerms,
    estimate_from_reports,
    mhe_estimate,
    shift,
)
from wheelload.estimators.mhe.terms import LOAD_SCALE, residual_function, terms_function
from wheelload.estimators.mhe.window import (
    TRAVEL_UNIT,
    WindowQP,
    bias_scales,
    ride_height_basis,
    travel_basis,
)
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.types import Sample, Signals
from wheelload.models import GATES, GRAVITY, INPUTS, ModelParameters, Vehicle, equilibrium_function
from wheelload.models.input_validity import MAX_INTERVAL
from wheelload.models.runtime import interrupts

#: m/s^2, the az of the made-up sample (level road, at rest) of the steady-state
#: covariance recursion. It reaches the covariance (az = 0 gives another one; a vehicle
#: file's hub-acceleration density weighs :math:`(a_{hub} - a_z)^2`), so it keeps the
#: value the steady-state arrival weight has always been computed with, not
#: :data:`~wheelload.models.GRAVITY` (9.80665).
STEADY_AZ = 9.81


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
        # The filter behind the window, sample by sample as in the C: no whole-log file check.
        self.filter = (
            ProjectionKF(
                vehicle, weighting=Weighting.MAXIMUM_PROBABILITY, static=static, check_file=False
            )
            if self.hard
            else TwoStageKF(vehicle, static=static, check_file=False)
        )
        self.p = self.filter.p
        self.tuning = self.filter.tuning
        A, _ = equilibrium_function()(np.zeros(len(INPUTS)), np.zeros(len(GATES)), self.p)
        self.A = np.asarray(A)
        self.null = null_vector(self.A)
        self.pinv = np.linalg.pinv(self.A)
        self.width = 1 if self.hard else 4
        self.load_bounds = (0.0, s.max_load) if s.bounded else (-math.inf, math.inf)
        mass = float(self.p[ModelParameters.names().index("mass")])
        #: N, :data:`LOAD_LIMIT` times the vehicle's weight
        self.load_limit = LOAD_LIMIT * mass * GRAVITY
        #: N^2, the filter's first prediction (m g)^2 I: a log starts with no prior
        self.diffuse_variance = variance_ceiling(mass)
        self.check = LoadCheck(
            hard=self.hard,
            null=self.null,
            bounds=self.load_bounds,
            limit=self.load_limit,
            eps=(s.solver.eps_abs, s.solver.eps_rel),
        )
        self.terms = terms_function(
            s.constraint,
            null=self.null,
            pinv=self.pinv,
            lower_load=self.load_bounds[0],
            upper_load=self.load_bounds[1],
        )
        self.workspace = MheWorkspace(s, self.width)
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

    @property
    def process_noise_density(self) -> float:
        """q of the filter's tuning (its Q = q dt I): the arrival cost's random walk."""
        return float(TUNING.value(self.tuning, "process_noise_density"))

    def cost_factor(self, dt: float) -> float:
        """Cost scale :math:`c`: the QP's Hessian :math:`c s^2 H` has diagonal entries near one."""
        q = self.process_noise_density
        r_s = TUNING.value(self.tuning, "suspension_noise_density")
        return 1.0 / (LOAD_SCALE**2 * (dt / r_s + 2.0 / (q * dt)))

    def steady_state_covariance(self, dt: float, samples: int = 20000) -> np.ndarray:
        """Fixed point of the filter covariance recursion at interval ``dt``, inputs all valid."""
        step = self.filter._step
        P = self.filter.initial_state().P
        u = np.zeros(len(INPUTS))
        u[INPUTS.index("az")] = STEADY_AZ
        valid = np.ones(len(INPUTS))
        for _ in range(samples):
            interrupts.check()  # a Ctrl-C the CasADi call swallowed
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
            steady = arrival_weights(
                steady[None], self.process_noise_density * np.array([dt]), cost
            )[0]
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
            state = replace(state, **initial_extended(self, x0))
        return state

    # -- per sample --------------------------------------------------------------------------

    def step(self, state: MheState, sample: Sample, dt: float) -> tuple[MheState, MheEstimate]:
        """Filter one sample, add its terms to the window and solve; returns the new state.

        Same numbers as :meth:`run` over the same samples from the same state. A
        non-positive or non-finite ``dt`` solves nothing: the state and the last
        estimate are held and flagged ``STEP_REJECTED`` (status 0).
        """
        interrupts.check()  # a Ctrl-C the last step's CasADi calls swallowed
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
        terms = SampleTerms(
            H, g, float(link[0]), xp, lower, upper, b, used, kf, estimate.std[0], rows
        )
        arrival = self._arrival(state, state.kf.P[None], np.array([dt]))[0]
        state, report = self._advance(state, terms, arrival)
        lag = self.settings.lag
        return state, estimate_from_reports(np.array([np.nan]), [report], self.A, lag=lag)

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
        weights = arrival_weights(previous, self.process_noise_density * dt, state.cost)
        first = (np.arange(len(dt)) + state.k == 0)[:, None, None]
        if self.settings.arrival is Arrival.STEADY_STATE:
            weights = np.where(first, weights, state.steady)
        # The log's first sample: the filter's diffuse prediction (no prior information).
        diffuse = state.cost * LOAD_SCALE**2 / self.diffuse_variance * np.eye(4)
        return np.where(first, diffuse, weights)

    def _advance(self, state: MheState, terms: SampleTerms, arrival: np.ndarray):
        """Push one sample's terms into the window, solve, and return the state and report."""
        if self.settings.extended:
            return advance_extended(self, state, terms, arrival)
        start = time.perf_counter()
        link = terms.link if state.k > 0 else 0.0  # the log's first sample: the arrival instead
        drift = link / LOAD_SCALE * float(self.null @ (terms.xp - state.xp[-1]))
        w = self.width
        window = dict(
            H=shift(state.H, terms.H.reshape(w, w)),
            g=shift(state.g, terms.g),
            link=shift(state.link, link),
            drift=shift(state.drift, drift if self.hard else 0.0),
            xp=shift(state.xp, terms.xp),
            lower=shift(state.lower, terms.lower),
            upper=shift(state.upper, terms.upper),
            arrival=shift(state.arrival, arrival),
        )
        N = self.settings.horizon
        j0 = max(0, N - 1 - state.k)
        prior = state.history[0]
        if state.k == 0:  # a new log: a fresh solver, so a run depends on its log alone
            self.workspace = MheWorkspace(self.settings, self.width)
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
            x_warm = prior_solution(window, j0, last, self.null, self.hard, x_warm, w)
            status, iterations = SOLVED, 0
            x = self.check.newest(x_warm[-w:], window)
        else:
            Px = hessian_values(window, j0, self.null, self.hard)
            q = linear_term(window, j0, prior, self.null, self.hard)
            bounds = (window["lower"].ravel(), window["upper"].ravel()) if state.y.size else None
            if finite_data(Px, q, *(bounds or ())):
                result, rho = self.workspace.solve(Px, q, bounds, x_warm, y_warm, state.rho)
                status, iterations = int(result.info.status_val), int(result.info.iter)
            else:
                status, iterations = UNSOLVED, 0
            if status == SOLVED:
                x_warm, y_warm = np.array(result.x), np.array(result.y)
                x = self.check.newest(x_warm[-w:], window)
        failed = x is None
        if failed:
            x = self.check.fallback(terms.kf.x, state.history[-1])
        kfx = shift(state.kfx, terms.kf.x)
        state = replace(
            state,
            k=state.k + 1,
            kf=terms.kf,
            history=shift(state.history, x),
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
            x = self.check.checked(block, sample.lower, sample.upper, sample.xp)
        else:
            w = self.width
            block = state.x[j * w : (j + 1) * w]
            x = self.check.checked(block, state.lower[j], state.upper[j], state.xp[j])
        return self.check.fallback(state.kfx[j], state.history[-1]) if x is None else x

    def bias_report(self, beta: np.ndarray) -> np.ndarray:
        """Bias states in reporting units: travel offsets FL..RR [m], then ax, ay [m/s^2]."""
        nd = self.settings.bias_states.travel_states
        if not nd:
            return beta
        offsets = self.travel_basis @ beta[:nd] * TRAVEL_UNIT
        return np.concatenate([offsets, beta[nd:]])

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
        state = state or self.initial_state(float(order_statistics.median(dt)))
        fallback, covariances = self.filter.run_with_covariance(signals, state.kf)
        u = input_matrix(signals, RateDerivativeFilter.of(self.filter.vehicle))
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
        interrupts.check()  # a Ctrl-C the mapped CasADi calls swallowed: before the loops
        previous = np.concatenate([state.kf.P[None], covariances[:-1]])
        arrival = self._arrival(state, previous, dt)
        if not self.settings.extended and not self.per_sample_states:
            return self._run_ring(signals, state, (H, g, link, xp, lower, upper, b, used),
                                  fallback, arrival)  # fmt: skip
        reports = []
        for k in range(n):
            kf = FilterState(fallback.loads[k], covariances[k])
            terms = SampleTerms(
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
        return estimate_from_reports(signals.t.copy(), reports, self.A, lag=lag)

    #: True: :meth:`run` advances the plain window through :meth:`_advance` and a new
    #: :class:`MheState` per sample (the reference the loop over a log is tested against)
    per_sample_states = False
    #: a list: the ring loop appends each solved QP's data to it (``wheelload bench mhe``)
    qp_record: list | None = None

    def _run_ring(self, signals: Signals, state: MheState, out: tuple, fallback, arrival):
        """The plain window's loop over whole-log arrays (:mod:`.ring`)."""
        H, g, link, xp, lower, upper, b, used = out
        loads, status, iterations, failed, solve_time, final = run_ring(
            self, state, H, g, link, xp, lower, upper, fallback.loads, arrival, self.qp_record
        )
        n, lag, N = len(signals), self.settings.lag, self.settings.horizon
        if lag:  # row i: the estimate of sample i; the log's last samples from its last window
            tail = [final(N - lag + m) for m in range(min(lag, n))]
            loads = np.vstack([loads[lag:], np.array(tail[max(0, lag - n) :]).reshape(-1, 4)])
        return mhe_estimate(
            signals.t.copy(), loads, fallback.std, b, used, self.A,
            status=status, iterations=iterations, fallback=failed, solve_time=solve_time,
            lag=lag, bias=None,
        )  # fmt: skip
