r"""The MHE window's quadratic program on OSQP: Hessian values, linear term, workspace, checks.

The window's cost (see :mod:`wheelload.estimators.mhe.estimator`) in the QP's units
(loads in kN, :data:`~wheelload.estimators.mhe.terms.LOAD_SCALE`) has a block-tridiagonal
upper-triangular Hessian: per sample :math:`H_j + (\ell_j + \ell_{j+1}) I`, the arrival
weight on the window's first sample :math:`j_0`, couplings :math:`-\ell_j I` to the sample
before (:func:`hessian_values`, in the CSC order of :func:`csc_value_order`); the linear
term :math:`q` holds the samples' terms, the random walk's drift and the arrival prior
(:func:`linear_term`). A window without data has the prior, carried unchanged, as its
minimiser (:func:`prior_solution`). :class:`MheWorkspace` holds the OSQP problem (an
unbounded window's without over-relaxation or scaling: :data:`UNCONSTRAINED_SETTINGS`);
:class:`LoadCheck` turns a sample's QP variables into loads within the bounds, or refuses.

Shared by the per-sample window (:mod:`~wheelload.estimators.mhe.estimator`) and the loop
over a log (:mod:`~wheelload.estimators.mhe.ring`).

Example
-------
>>> workspace = MheWorkspace(MheSettings(horizon=10), width=4)
>>> result, rho = workspace.solve(Px, q, None, x, y, rho)
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import osqp
import scipy.sparse as sp

from wheelload.estimators.mhe.quiet import quiet_stdout
from wheelload.estimators.mhe.settings import MheSettings
from wheelload.estimators.mhe.terms import LOAD_SCALE
from wheelload.models.runtime import interrupts

SOLVED = osqp.SolverStatus.OSQP_SOLVED.value
#: Status of a sample whose QP data are not finite: not handed to OSQP, the filter's estimate.
UNSOLVED = osqp.SolverStatus.OSQP_UNSOLVED.value
#: Status of a solve OSQP's own SIGINT handler stopped: a Ctrl-C that Python never saw.
INTERRUPTED = osqp.SolverStatus.OSQP_SIGINT.value
#: OSQP's infinity: bounds beyond it are clamped to it (as its Python wrapper does).
OSQP_INFINITY = osqp.constant("OSQP_INFTY")
#: Largest :math:`|F_z|` [m g] an estimate may take: a QP solution beyond it is not
#: solved (the filter's estimate), a filter estimate beyond it is not taken (the last
#: estimate is held). No road wheel carries twice the vehicle's weight.
LOAD_LIMIT = 2.0
#: OSQP settings of a window without constraints (unbounded): ADMM's x-step,
#: :math:`(P + \sigma I)\,\tilde x = \sigma x_k - q`, is then the minimiser itself (to
#: :math:`\sigma` = 1e-6), so OSQP's over-relaxation (:math:`\alpha` = 1.6) only makes the
#: error of the warm start decay by :math:`|1 - \alpha|` = 0.6 per iteration (20-25
#: iterations at 1e-6), and its Ruiz scaling, recomputed at every Hessian update, only costs
#: time (measured on the soft window, N = 20, generated C: 30 % of a sample). Without both,
#: the solve ends at the first termination check. The generated C has the same settings
#: (it is generated from this workspace).
UNCONSTRAINED_SETTINGS = {"alpha": 1.0, "scaling": 0}


def arrival_weights(P: np.ndarray, q_dt: np.ndarray, cost: float) -> np.ndarray:
    r""":math:`c s^2 (P + q\,dt\,I)^{-1}`, symmetrised, for each of the stacked ``P``."""
    W = np.linalg.inv(P + q_dt[:, None, None] * np.eye(4))
    return cost * LOAD_SCALE**2 * 0.5 * (W + W.transpose(0, 2, 1))


def prior_solution(
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


def hessian_values(window: dict, j0: int, null: np.ndarray, hard: bool) -> np.ndarray:
    """Values of the window's upper-triangular Hessian in CSC order (:func:`csc_value_order`)."""
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
    return values[csc_value_order(N, 1 if hard else 4)]


def linear_term(
    window: dict, j0: int, prior: np.ndarray, null: np.ndarray, hard: bool
) -> np.ndarray:
    """The window's linear term ``q``: samples' terms, random-walk drift, arrival prior."""
    q = window["g"].copy()
    W = window["arrival"][j0]
    if hard:
        drift = window["drift"][1:]
        q[1:, 0] += drift
        q[:-1, 0] -= drift
        q[j0, 0] += arrival_pull((null @ W).tolist(), window["xp"][j0].tolist(), prior.tolist())
    else:
        q[j0] -= W @ prior / LOAD_SCALE
    return q.ravel()


def arrival_pull(nW: list, xp: list, prior: list) -> float:
    r"""The hard window's arrival prior on its oldest warp variable,
    :math:`n^\top W (\bar x_p - \hat x) / s` (:math:`nW = n^\top W`, :math:`s` =
    :data:`LOAD_SCALE`), in plain floats summed wheel by wheel (the same bits on every path:
    the per-sample state and the loop over a log, :func:`.ring.run_hard`)."""
    return (
        nW[0] * (xp[0] - prior[0])
        + nW[1] * (xp[1] - prior[1])
        + nW[2] * (xp[2] - prior[2])
        + nW[3] * (xp[3] - prior[3])
    ) / LOAD_SCALE


def check_interrupted(status: int) -> None:
    """KeyboardInterrupt when OSQP stopped the solve on Ctrl-C (:data:`INTERRUPTED`), so that
    the press stops the run instead of a sample falling back to the filter's estimate
    (:func:`wheelload.models.runtime.interrupts.caught`)."""
    if status == INTERRUPTED:
        interrupts.caught()


def low_level(solver: osqp.OSQP):
    """OSQP's solver object behind its Python wrapper (``update_data_vec``, ``update_data_mat``).

    The only reach into OSQP's private ``_solver``: the wrapper offers neither the
    :math:`\\rho` it adapted during a solve nor updates and solves without building its
    result namespace, which the loop over a log (:mod:`~wheelload.estimators.mhe.ring`) and
    the extended window (:meth:`.window.WindowQP.solve_raw`) skip per sample.
    """
    return solver._solver


class MheWorkspace:
    """The window's OSQP problem, set up once with placeholder values and updated per sample.

    It remembers the values it holds (Hessian, bounds, :math:`\\rho`) and
    updates only what differs, so a state from elsewhere gives the same
    numbers as the one it continued from.
    """

    def __init__(self, settings: MheSettings, width: int) -> None:
        N = settings.horizon
        dimension = N * width
        P = hessian_pattern(N, width)
        placeholder = np.concatenate(
            [np.eye(width).ravel()] * N + [np.full((N - 1) * width, -0.25)]
        )
        P.data = placeholder[csc_value_order(N, width)]
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
            **({} if settings.bounded else UNCONSTRAINED_SETTINGS),
        )  # fmt: skip

    @property
    def low_level(self):
        """OSQP's solver object behind this workspace's wrapper (:func:`low_level`)."""
        return low_level(self.solver)

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
        with quiet_stdout(self.polish):
            result = solver.solve(raise_error=False)
        check_interrupted(result.info.status_val)
        self.rho = self.low_level.get_settings().rho  # adapted during the solve
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


def clip_checked(value, low, high, eps: tuple[float, float]):
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


def null_vector(A: np.ndarray) -> np.ndarray:
    """Unit vector spanning the null space of the rank-3 equilibrium matrix (the warp mode)."""
    _, singular, Vt = np.linalg.svd(A)
    if singular[-1] < 1e-9 * singular[0]:
        raise ValueError("equilibrium matrix A has rank below 3: check the vehicle geometry")
    nv = Vt[-1]
    return nv if nv[0] >= 0 else -nv


def hessian_pattern(N: int, width: int) -> sp.csc_matrix:
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
def csc_value_order(N: int, width: int) -> np.ndarray:
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


@dataclass(frozen=True, eq=False)
class LoadCheck:
    """Loads [N] from a sample's QP variables within the bounds and :data:`LOAD_LIMIT`."""

    hard: bool  # the QP variable is the warp amplitude omega
    null: np.ndarray  # (4,) the equilibrium's unit null vector n
    bounds: tuple[float, float]  # N, load bounds
    limit: float  # N, LOAD_LIMIT times the vehicle's weight
    eps: tuple[float, float]  # OSQP's (eps_abs, eps_rel)

    def plausible(self, x) -> bool:
        """True when every load is finite and within :attr:`limit` (NaN fails)."""
        limit = self.limit
        return all(abs(value) <= limit for value in np.asarray(x, dtype=float).tolist())

    def fallback(self, filtered: np.ndarray, held: np.ndarray) -> np.ndarray:
        """The loads of a sample whose QP is not solved: the filter's, clipped to the bounds.

        A filter estimate that is not finite or beyond :attr:`limit` is not
        taken: ``held`` (the last estimate) is, so no output is ever non-finite.
        """
        source = filtered if self.plausible(filtered) else held
        return np.clip(source, *self.bounds)

    def checked(self, block, lower, upper, xp) -> np.ndarray | None:
        r"""Loads [N] from one sample's QP variables, or None if out of bounds.

        Hard constraint: a collapsed warp interval (``lower == upper``, no bounded loads
        satisfy the equilibrium, :func:`~wheelload.estimators.mhe.terms.warp_interval`)
        gives :math:`A^+ b + n\,\omega` at its midpoint clipped to the bounds, a solved
        sample; elsewhere the loads must lie within the bounds up to rounding.
        """
        clipped = clip_checked(block, lower, upper, self.eps)
        if clipped is None:
            return None
        if not self.hard:
            x = clipped * LOAD_SCALE
        else:
            x = xp + self.null * (clipped[0] * LOAD_SCALE)
            if float(lower[0]) == float(upper[0]):
                x = np.clip(x, *self.bounds)
            else:
                x = clip_checked(x, *self.bounds, (1e-9, 1e-12))
        return x if x is not None and self.plausible(x) else None

    def newest(self, last: np.ndarray, window: dict) -> np.ndarray | None:
        """The newest sample's loads [N] from its QP variables, or None (:meth:`checked`)."""
        return self.checked(last, window["lower"][-1], window["upper"][-1], window["xp"][-1])
