r"""Rauch–Tung–Striebel smoother over the two-stage KF, a backward pass in compiled C.

With the filter's posterior :math:`x_{k|k}, P_{k|k}` and its prediction
:math:`x_{k+1|k}, P_{k+1|k}` (Rauch, Tung & Striebel 1965; Särkkä 2013 §8.2):

.. math::
    C_k = P_{k|k} P_{k+1|k}^{-1}, \quad
    x^s_k = x_{k|k} + C_k (x^s_{k+1} - x_{k+1|k}), \quad
    P^s_k = P_{k|k} + C_k (P^s_{k+1} - P_{k+1|k}) C_k^\top

The prediction is the filter's own step Function with every input marked
missing (no update runs, only the random walk :math:`Q = q\,dt\,I`), so the
smoother follows any change to the filter's model. The backward step is one
CasADi Function looped over the reversed log in generated C
(:class:`~wheelload.estimators.loops.compiled.CompiledLoop`), like ``TwoStageKF.run``.

Example
-------
>>> smoothed = TwoStageKF(vehicle).smooth(read_log("drive.csv"))
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.result import Estimate

SMOOTHER_NAME = "wheelload_rts_step"
#: The smoothed σ: the RTS covariance of the filter's random-walk model, without the
#: reported-σ model's calibration (``estimators/kf/reported_std.py``).
RTS_STD_SOURCE = "the RTS covariance √diag Pˢ (random-walk model, no reported-σ calibration)"


def smoother_function(step: ca.Function) -> ca.Function:
    """``wheelload_rts_step(xs, Ps, x, P, dt, p, tuning) -> (xs_prev, Ps_prev, std)``.

    ``x, P``: the filter's posterior at sample k; ``dt``: the interval before
    sample k + 1; ``xs, Ps``: the smoothed estimate of sample k + 1.
    """
    xs = ca.SX.sym("xs", 4)
    Ps = ca.SX.sym("Ps", 4, 4)
    x = ca.SX.sym("x", 4)
    P = ca.SX.sym("P", 4, 4)
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", step.size1_in("p"))
    tuning = ca.SX.sym("tuning", step.size1_in("tuning"))
    n_u = step.size1_in("u")
    predicted = step(
        x=x, P=P, u=ca.DM.zeros(n_u), u_valid=ca.DM.zeros(n_u), dt=dt, p=p, tuning=tuning
    )
    x_pred, P_pred = predicted["x_next"], predicted["P_next"]
    C = ca.solve(P_pred, P).T  # P P_pred^-1 with both symmetric
    x_s = x + ca.mtimes(C, xs - x_pred)
    P_s = P + ca.mtimes([C, Ps - P_pred, C.T])
    P_s = 0.5 * (P_s + P_s.T)
    std = ca.sqrt(ca.fmax(ca.diag(P_s), 0))
    return ca.Function(
        SMOOTHER_NAME, [xs, Ps, x, P, dt, p, tuning], [x_s, P_s, std],
        ["xs", "Ps", "x", "P", "dt", "p", "tuning"], ["xs_prev", "Ps_prev", "std"],
    )  # fmt: skip


@functools.cache
def _loop(step: ca.Function) -> CompiledLoop:
    return CompiledLoop(smoother_function(step), 2, ("x", "P", "dt"))


def rts_smooth(
    filtered: Estimate, covariances: np.ndarray, dt: np.ndarray, step, p, tuning, A
) -> Estimate:
    """The smoothed :class:`Estimate` of a filtered log (see module docstring).

    ``covariances`` (n, 4, 4) are the filter's posteriors, ``dt`` the interval
    before each sample, ``A`` the equilibrium matrix for the residuals.
    """
    n = len(filtered)
    if n < 2:
        return filtered
    x = filtered.loads
    P = covariances.reshape(n, 16, order="C")  # symmetric: C and F order agree
    order = np.arange(n - 2, -1, -1)
    _, history, (std,) = _loop(step)(
        [x[-1], covariances[-1]],
        [p, tuning],
        [x[order], P[order], dt[order + 1, None]],
        record=(0,),
    )
    loads = np.vstack([history[0][::-1], x[-1:]])
    # The smoothed sigma is the RTS covariance's (the reported-sigma model is the filter's).
    last = np.sqrt(np.fmax(np.diagonal(covariances[-1]), 0.0))
    std = np.vstack([std[::-1], last[None, :]])
    residual = filtered.residual + (filtered.loads - loads) @ np.asarray(A).T
    return Estimate(
        t=filtered.t.copy(),
        loads=loads,
        std=std,
        residual=residual,
        flags=filtered.flags.copy(),
        std_source=RTS_STD_SOURCE,
    )
