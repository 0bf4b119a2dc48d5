r"""The MHE window with robust losses and bias states: one QP, set up once with fixed sparsity.

Each residual row :math:`i` of sample :math:`j` in units of its standard
deviation, :math:`\rho = \sqrt{w}\,r` (:math:`w = dt/r`, masked as in the
filter), costs

.. math::
    \text{quadratic: } \tfrac12 \rho^2, \qquad
    \text{Huber}_\delta: \min_{e} \tfrac12 (\rho - e)^2 + \delta |e|, \qquad
    \text{L1: } \min_e \tfrac{1}{2\varepsilon}(\rho - e)^2 + |e|

with the auxiliary :math:`e = e^+ - e^-`, :math:`e^\pm \ge 0` (Huber 1964; the
auxiliary-variable QP of Mangasarian & Musicant 2000). L1 is realised with a
quadratic core of width :math:`\varepsilon` = :data:`L1_CORE` σ: it equals
:math:`|\rho| - \varepsilon/2` outside the core. Losses are chosen per
residual group (suspension rows, equilibrium rows).

Bias states :math:`\beta` are constant over the window and enter the
residuals linearly, through the model Functions' Jacobians at the sample
(exact for the paper's model; with the stops engaged it is the local slope, and
an offset's effect on the road-frame attitude in :math:`b` is left out, under
6 % of its effect through :math:`J_d` on the bundled car): travel offsets
:math:`\delta` shift the pseudo-measurement,
:math:`z(d - \delta) = z(d) - J_d\,\delta`, and ax/ay biases shift the
equilibrium right-hand side, :math:`b(a - \beta_a) = b(a) - B_a \beta_a`, with
:math:`J_d, B_a` the model Functions' Jacobians. Travel offsets are estimated in a basis
:math:`\delta = T\gamma`: the three combinations the window observes
(:func:`travel_basis`) or one offset per axle (:func:`ride_height_basis`);
ax/ay or ay alone (see :class:`BiasStates`). Their arrival cost is
:math:`\|\beta - \bar\beta\|^2_{\Pi_\beta^{-1}}` with :math:`\bar\beta` the
previous window's estimate and the information :math:`\Pi_\beta^{-1}` carried
as in a filter: it loses :math:`q_\beta\,dt` of variance per sample (random
walk) and gains the bias information of each sample that leaves the window
(its rows' Schur complement with the sample's loads eliminated, with the
loss's effective weights). Bounds :math:`|\beta| \le \beta_{max}` hold in the QP.

The QP (variables in kN, :math:`e` in σ, travel offsets in mm, accelerations
in m/s²) has a fixed upper-triangular pattern, found at set-up. Per sample only
its values are formed (:meth:`WindowQP.assemble_values`): each term's entries
go to precomputed positions in OSQP's CSC value array and are summed there
(``numpy.bincount``), so the dense :math:`n \times n` matrix of
:meth:`WindowQP.assemble` (kept as the reference) is never built. The
constraints are the identity (bounds on every variable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import osqp
import scipy.sparse as sp

from wheelload.estimators.mhe.qp import OSQP_INFINITY, check_interrupted, low_level
from wheelload.estimators.mhe.quiet import quiet_stdout
from wheelload.estimators.mhe.settings import L1_CORE, BiasStates, Loss, ResidualLoss

TRAVEL_UNIT = 1e-3  # m: travel offsets are QP variables in mm


def bias_scales(bias: BiasStates, vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Initial std, bound and random-walk density of each bias variable (QP units)."""
    tuning = vehicle.filter.bias
    nd, na = bias.travel_states, len(bias.acceleration_columns)
    std = [tuning.travel_offset_std / TRAVEL_UNIT] * nd + [tuning.acceleration_bias_std] * na
    bound = [tuning.travel_offset_bound / TRAVEL_UNIT] * nd
    bound += [tuning.acceleration_bias_bound] * na
    density = [tuning.travel_offset_density / TRAVEL_UNIT**2] * nd
    density += [tuning.acceleration_bias_density] * na
    return np.array(std), np.array(bound), np.array(density)


def travel_basis(Jd: np.ndarray, null: np.ndarray) -> np.ndarray:
    r"""Orthonormal basis :math:`T` (4 x 3) of the travel offsets the window can observe.

    An offset pattern whose load shift :math:`J_d\,\delta` lies along the warp
    vector :math:`n` (the equilibrium's null space) is absorbed by the loads'
    warp mode and cannot be told from a true warp load; offsets are
    estimated as :math:`\delta = T\gamma` with :math:`n^\top J_d T = 0`. A
    left-right symmetric offset (ride height) lies in the span; a single
    corner's offset is recovered as its projection onto it.
    """
    _, _, Vt = np.linalg.svd((null @ Jd)[None, :])
    return Vt[1:].T


def ride_height_basis() -> np.ndarray:
    r"""Basis (4 x 2) of per-axle offsets, both sensors of an axle alike (unit columns).

    Orthogonal to the warp for a left-right symmetric suspension:
    :math:`n^\top J_d T = 0` (tested).
    """
    return np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]) / math.sqrt(2.0)


@dataclass(frozen=True, eq=False)
class WindowSample:
    """What one sample contributes (physical units; ``ls, lc`` are the rows' sqrt weights)."""

    z: np.ndarray  # (4,) pseudo-measurement [N]
    Jd: np.ndarray  # (4, 4) dz/dd [N/m]
    b: np.ndarray  # (3,) equilibrium right-hand side
    Ba: np.ndarray  # (3, na) db/d(ax, ay), the columns with a bias state
    ls: np.ndarray  # (4,) sqrt(mask dt / r_s) [1/N]
    lc: np.ndarray  # (3,) sqrt(mask dt / r_c)
    xp: np.ndarray  # (4,) hard: A^+ b [N]; soft: zeros
    link: float  # 1/(q dt) [1/N^2]; 0 for the log's first sample
    lower: np.ndarray  # (w,) bounds of the load variables (kN or warp kN)
    upper: np.ndarray  # (w,)


class WindowQP:
    """Layout, dense assembly and the OSQP workspace of the extended window."""

    def __init__(self, *, horizon: int, hard: bool, A: np.ndarray, null: np.ndarray,
                 suspension: ResidualLoss, constraint: ResidualLoss, n_bias: int,
                 travel_basis: np.ndarray | None, solver) -> None:  # fmt: skip
        self.N, self.hard, self.A, self.null = horizon, hard, A, null
        self.suspension, self.constraint = suspension, constraint
        self.w = 1 if hard else 4
        self.ns = 4 if suspension.robust else 0  # auxiliary pairs per sample
        self.nc = 3 if (constraint.robust and not hard) else 0
        self.width = self.w + 2 * self.ns + 2 * self.nc
        self.n_bias, self.travel_bias = n_bias, travel_basis is not None
        self.travel_basis = travel_basis if travel_basis is not None else np.zeros((4, 0))
        self.n = self.N * self.width + n_bias
        self.X = 1000.0 * (null[:, None] if hard else np.eye(4))  # x = xp + X y
        self.solver_settings = solver
        self.pinv = np.linalg.pinv(A)
        beta = np.arange(self.N * self.width, self.n)
        self.columns = [
            np.concatenate([np.arange(j * self.width, (j + 1) * self.width), beta])
            for j in range(self.N)
        ]
        self.blocks = [np.ix_(c, c) for c in self.columns]
        # a sample's own block and the bias: columns[j] ascend, so local upper = global upper
        self.local_upper = np.triu_indices(self.width + n_bias)
        upper_pattern = np.triu(self._structure()) != 0
        self.rows, self.cols = np.nonzero(upper_pattern.T)  # CSC order: by column, then row
        self.cols, self.rows = self.rows, self.cols
        self.setup()
        self._value_positions()

    def setup(self) -> None:
        """A fresh OSQP workspace with the fixed pattern."""
        s = self.solver_settings
        placeholder = (self.rows == self.cols).astype(float)  # identity values: convex
        P = sp.csc_matrix((placeholder, (self.rows, self.cols)), shape=(self.n, self.n))
        P.sort_indices()
        if P.nnz != self.rows.size:
            raise RuntimeError("the window's Hessian pattern lost entries")
        self.order = np.lexsort((self.rows, self.cols))
        self.solver = osqp.OSQP()
        self.solver.setup(
            P, np.zeros(self.n), sp.identity(self.n, format="csc"),
            -np.ones(self.n), np.ones(self.n),
            verbose=False, eps_abs=s.eps_abs, eps_rel=s.eps_rel, max_iter=s.max_iter,
            polishing=s.polish, check_termination=s.check_termination,
            adaptive_rho_interval=s.adaptive_rho_interval, rho=s.rho, warm_starting=True,
        )  # fmt: skip

    def y(self, j: int) -> slice:
        start = j * self.width
        return slice(start, start + self.w)

    def aux(self, j: int, group: int) -> tuple[slice, slice]:
        """(e+, e-) of the suspension (0) or equilibrium (1) group of sample ``j``."""
        start = j * self.width + self.w + (0 if group == 0 else 2 * self.ns)
        size = self.ns if group == 0 else self.nc
        return slice(start, start + size), slice(start + size, start + 2 * size)

    @property
    def beta(self) -> slice:
        return slice(self.N * self.width, self.n)

    def _structure(self) -> np.ndarray:
        """Every entry that can be non-zero (assembled with all-one data, arrival everywhere)."""
        one = WindowSample(
            z=np.ones(4), Jd=np.ones((4, 4)), b=np.ones(3),
            Ba=np.ones((3, self.n_bias - self.travel_basis.shape[1])),
            ls=np.ones(4), lc=np.ones(3), xp=np.ones(4), link=1.0,
            lower=np.zeros(self.w), upper=np.ones(self.w),
        )  # fmt: skip
        total = np.zeros((self.n, self.n))
        local = [self.local_terms(one)] * self.N
        for j0 in range(self.N):
            H, _ = self.assemble([one] * self.N, j0, np.ones(4), np.ones((4, 4)),
                                 np.ones(self.n_bias), np.ones((self.n_bias, self.n_bias)),
                                 local, 1.0)  # fmt: skip
            total += np.abs(H)
        return total + np.eye(self.n)

    def local_terms(self, sample: WindowSample) -> tuple[np.ndarray, np.ndarray]:
        """One sample's data rows as (H, g) over its own block and the bias (physical units).

        Computed once when the sample enters the window; :meth:`assemble`
        adds it at the sample's place.
        """
        size = self.width + self.n_bias
        H = np.zeros((size, size))
        g = np.zeros(size)
        y = np.arange(self.w)
        beta = np.arange(self.width, size)
        nd = self.travel_basis.shape[1]
        # suspension rows: rho = ls (z - xp - X y - Jd delta)
        Ms = np.zeros((4, self.w + self.n_bias))
        Ms[:, : self.w] = -self.X
        if nd:
            Ms[:, self.w : self.w + nd] = -sample.Jd @ self.travel_basis * TRAVEL_UNIT
        if self.hard and self.n_bias > nd:  # x = A^+ (b - Ba beta_a) + n omega
            Ms[:, self.w + nd :] = self.pinv @ (sample.Ba * (sample.lc > 0)[:, None])
        Ms *= sample.ls[:, None]
        rs = -sample.ls * (sample.z - sample.xp)
        self._rows(H, g, y, beta, Ms, rs, self.suspension, self.aux(0, 0))
        if not self.hard:  # equilibrium rows: rho = lc (b - Ba beta_a - A X y)
            Mc = np.zeros((3, self.w + self.n_bias))
            Mc[:, : self.w] = -self.A @ self.X
            if self.n_bias > nd:
                Mc[:, self.w + nd :] = -sample.Ba
            Mc *= sample.lc[:, None]
            rc = -sample.lc * sample.b
            self._rows(H, g, y, beta, Mc, rc, self.constraint, self.aux(0, 1))
        return H, g, H[self.local_upper]

    def _value_positions(self) -> None:
        """Where each term's upper-triangular entries go in the CSC value array.

        ``position[r, c]`` is the index of entry (r, c) in OSQP's ``Px`` (CSC
        order), or ``nnz`` (a bin dropped after the sum) outside the pattern,
        as :meth:`solve_raw` reads ``H[rows, cols][order]`` of the dense matrix.
        """
        N, w = self.N, self.w
        nnz = self.rows.size
        position = np.full((self.n, self.n), nnz)
        position[self.rows[self.order], self.cols[self.order]] = np.arange(nnz)
        self.nnz = nnz
        a, b = self.local_upper
        self.local_positions = np.array([position[c[a], c[b]] for c in self.columns])
        self.local_columns = np.array(self.columns)
        ya, yb = np.triu_indices(w)
        y = [np.arange(self.y(j).start, self.y(j).stop) for j in range(N)]
        self.arrival_upper = (ya, yb)
        self.arrival_positions = [position[yj[ya], yj[yb]] for yj in y]
        # random-walk link of sample j: 1/2 link ||X y_j - X y_{j-1} - (xp_j - xp_{j-1})||^2
        self.link_matrix = np.hstack([self.X, -self.X])
        pair = [np.concatenate([y[j], y[j - 1]]) for j in range(1, N)]
        # y_{j-1} precedes y_j: the pair's global upper entries (the same for every j)
        la, lb = np.nonzero(np.less_equal.outer(pair[0], pair[0])) if pair else ([], [])
        self.link_upper = (la, lb)
        self.link_positions = np.array([position[c[la], c[lb]] for c in pair], dtype=int)
        self.link_columns = np.array(pair, dtype=int).reshape(N - 1, 2 * w)
        self.inert_positions = np.array([position[yj, yj] for yj in y])
        beta = np.arange(self.beta.start, self.beta.stop)
        ba, bb = np.triu_indices(self.n_bias)
        self.beta_upper = (ba, bb)
        self.beta_positions = position[beta[ba], beta[bb]]
        self.beta_columns = beta
        self._indices: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _indices_at(self, j0: int) -> tuple[np.ndarray, np.ndarray]:
        """(value positions, linear-term columns) of every term of a window starting at j0."""
        if j0 not in self._indices:
            y0 = np.arange(self.y(j0).start, self.y(j0).stop)
            self._indices[j0] = (
                np.concatenate([
                    self.local_positions[j0:].ravel(), self.arrival_positions[j0],
                    self.link_positions[j0:].ravel(), self.inert_positions[:j0].ravel(),
                    self.beta_positions,
                ]),
                np.concatenate([
                    self.local_columns[j0:].ravel(), y0, self.link_columns[j0:].ravel(),
                    self.beta_columns,
                ]),
            )  # fmt: skip
        return self._indices[j0]

    def assemble_values(self, window, j0, prior, arrival, beta_prior, beta_info, local, cost):
        """:meth:`assemble` as OSQP's ``Px`` (CSC values at the fixed pattern) and ``q``.

        The same terms, summed at their positions instead of in a dense matrix;
        equal to ``assemble``'s ``H[rows, cols][order]`` and ``g`` to rounding
        (the link's weight multiplies :math:`M^\top M` instead of :math:`M^\top`).
        """
        positions, columns = self._indices_at(j0)
        xp = np.array([s.xp for s in window])
        links = np.array([s.link for s in window[j0 + 1 :]])
        W = np.asarray(arrival, dtype=float)
        MW = self.X.T @ W
        # _add's arithmetic for each link: MW = M^T diag(link), H += MW M, g -= MW r
        linked = links[:, None, None] * self.link_matrix.T
        residual = (xp[j0:-1] - xp[j0 + 1 :])[:, :, None]  # r = -(xp_j - xp_{j-1})
        values = np.concatenate([
            np.concatenate([term[2] for term in local[j0:]]),
            (MW @ self.X)[self.arrival_upper],
            (linked @ self.link_matrix)[:, self.link_upper[0], self.link_upper[1]].ravel(),
            np.full(j0 * self.w, 1.0 / cost),
            np.asarray(beta_info, dtype=float)[self.beta_upper],
        ])  # fmt: skip
        linear = np.concatenate([
            np.concatenate([term[1] for term in local[j0:]]),
            -(MW @ (prior - xp[j0])),
            -(linked @ residual).ravel(),
            -(np.asarray(beta_info, dtype=float) @ beta_prior),
        ])  # fmt: skip
        Px = np.bincount(positions, values, minlength=self.nnz + 1)[: self.nnz]
        q = np.bincount(columns, linear, minlength=self.n)
        return cost * Px, cost * q

    def assemble(self, window, j0, prior, arrival, beta_prior, beta_info, local, cost):
        """Dense Hessian and linear term of the window (physical costs times ``cost``).

        ``arrival`` is :math:`\\Pi^{-1}` [1/N^2]; ``beta_info`` :math:`\\Pi_\beta^{-1}`;
        ``local`` each sample's :meth:`local_terms`.
        """
        H = np.zeros((self.n, self.n))
        g = np.zeros(self.n)
        beta = np.arange(self.beta.start, self.beta.stop)
        for j, sample in enumerate(window):
            y = np.arange(self.y(j).start, self.y(j).stop)
            if j < j0:
                H[y, y] += 1.0 / cost  # inert: unit diagonal after scaling
                continue
            Hl, gl, _ = local[j]
            H[self.blocks[j]] += Hl
            g[self.columns[j]] += gl
            if j == j0:
                self._add(H, g, y, self.X, prior - sample.xp, arrival)
            elif sample.link > 0:
                before = np.arange(self.y(j - 1).start, self.y(j - 1).stop)
                M = np.hstack([self.X, -self.X])
                r = -(sample.xp - window[j - 1].xp)
                self._add(H, g, np.concatenate([y, before]), M, r, sample.link)
        if self.n_bias:
            self._add(H, g, beta, np.eye(self.n_bias), beta_prior, beta_info)
        return cost * H, cost * g

    def _add(self, H, g, columns, M, r, weight):
        """Add 1/2 ||M v[columns] - r||^2_W to (H, g); ``weight`` scalar, vector or matrix."""
        W = np.asarray(weight, dtype=float)
        if W.ndim < 2:
            W = np.diag(np.broadcast_to(W, (M.shape[0],)))
        MW = M.T @ W
        H[np.ix_(columns, columns)] += MW @ M
        g[columns] -= MW @ r

    def _rows(self, H, g, y, beta, M, r, loss: ResidualLoss, aux) -> None:
        """One group's rows with its loss; M acts on [y, beta]."""
        columns = np.concatenate([y, beta])
        if not loss.robust or (self.hard and aux[0].stop == aux[0].start):
            self._add(H, g, columns, M, r, 1.0)
            return
        kappa, mu = loss.weights()
        plus, minus = aux
        k = M.shape[0]
        full = np.hstack([M, -np.eye(k), np.eye(k)])
        columns = np.concatenate([columns, np.arange(plus.start, plus.stop),
                                  np.arange(minus.start, minus.stop)])  # fmt: skip
        self._add(H, g, columns, full, r, kappa)
        g[plus] += mu
        g[minus] += mu

    def bounds(self, window, j0, beta_bound) -> tuple[np.ndarray, np.ndarray]:
        """Load bounds of each sample from ``j0`` (inert ones pinned at 0), aux >= 0, bias box."""
        low = np.zeros(self.n)
        high = np.zeros(self.n)
        N, w = self.N, self.w
        blocks_low = low[: N * self.width].reshape(N, self.width)
        blocks_high = high[: N * self.width].reshape(N, self.width)
        blocks_low[j0:, :w] = [sample.lower for sample in window[j0:]]
        blocks_high[j0:, :w] = [sample.upper for sample in window[j0:]]
        blocks_high[j0:, w:] = np.inf  # the auxiliaries e+, e- >= 0
        low[self.beta], high[self.beta] = -beta_bound, beta_bound
        return np.maximum(low, -osqp.constant("OSQP_INFTY")), np.minimum(
            high, osqp.constant("OSQP_INFTY")
        )

    def solve(self, H, g, low, high, x, y):
        """Load values at the fixed pattern, warm-start and solve."""
        self.solver.update(Px=H[self.rows, self.cols][self.order], q=g, l=low, u=high)
        self.solver.warm_start(x=x, y=y)
        with quiet_stdout(self.solver_settings.polish):
            result = self.solver.solve(raise_error=False)
        check_interrupted(result.info.status_val)
        return result

    def solve_raw(self, Px, g, low, high, x, y) -> tuple[int, int, np.ndarray, np.ndarray]:
        """:meth:`solve` through OSQP's solver object: ``(status, iterations, x, y)``.

        ``Px``: the Hessian's values in CSC order (:meth:`assemble_values`). The
        same calls in the same order as the wrapper makes them (vectors, then
        the matrix; bounds clamped to OSQP's infinity), without its result object.
        """
        solver = low_level(self.solver)
        solver.update_data_vec(
            q=g, l=np.maximum(low, -OSQP_INFINITY), u=np.minimum(high, OSQP_INFINITY)
        )
        solver.update_data_mat(P_x=Px, P_i=None, A_x=None, A_i=None)
        solver.warm_start(x, y)
        with quiet_stdout(self.solver_settings.polish):
            solver.solve()
        info = solver.info
        check_interrupted(info.status_val)
        return int(info.status_val), int(info.iter), solver.solution.x, solver.solution.y

    def bias_information(self, sample: WindowSample, rho_s, rho_c) -> np.ndarray:
        """The bias information of one sample with its loads eliminated (Schur complement).

        Rows take the loss's effective weight at the solution's residuals
        (Huber: ``min(1, delta/|rho|)``), so an outlier adds little.
        """
        nd = self.travel_basis.shape[1]
        M, weights = [], []
        Ms = np.zeros((4, self.w + self.n_bias))
        Ms[:, : self.w] = -self.X
        if nd:
            Ms[:, self.w : self.w + nd] = -sample.Jd @ self.travel_basis * TRAVEL_UNIT
        if self.hard and self.n_bias > nd:
            Ms[:, self.w + nd :] = self.pinv @ (sample.Ba * (sample.lc > 0)[:, None])
        M.append(Ms * sample.ls[:, None])
        weights.append(effective_weights(self.suspension, rho_s))
        if not self.hard:
            Mc = np.zeros((3, self.w + self.n_bias))
            Mc[:, : self.w] = -self.A @ self.X
            if self.n_bias > nd:
                Mc[:, self.w + nd :] = -sample.Ba
            M.append(Mc * sample.lc[:, None])
            weights.append(effective_weights(self.constraint, rho_c))
        M = np.vstack(M)
        F = M.T @ (np.concatenate(weights)[:, None] * M)
        Fyy, Fyb, Fbb = F[: self.w, : self.w], F[: self.w, self.w :], F[self.w :, self.w :]
        return Fbb - Fyb.T @ np.linalg.solve(Fyy + 1e-12 * np.eye(self.w), Fyb)


def effective_weights(loss: ResidualLoss, rho: np.ndarray) -> np.ndarray:
    """Effective quadratic weight of each row at residual ``rho`` [σ] (IRLS weight)."""
    if not loss.robust:
        return np.ones_like(rho)
    corner = loss.threshold if loss.kind is Loss.HUBER else L1_CORE
    scale = 1.0 if loss.kind is Loss.HUBER else 1.0 / L1_CORE
    return scale * np.minimum(1.0, corner / np.maximum(np.abs(rho), 1e-12))
