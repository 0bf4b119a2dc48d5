r"""The extended MHE window (robust losses, bias states) advanced by one sample.

The window of :mod:`~wheelload.estimators.mhe.window` (Huber / L1 losses through auxiliary
variables, bias states :math:`\beta` with the arrival cost
:math:`\|\beta - \bar\beta\|^2_{\Pi_\beta^{-1}}`): each sample's residual rows join the
window, its QP is assembled and solved, the bias estimate is clipped to its bounds, and the
information :math:`\Pi_\beta^{-1}` loses :math:`q_\beta\,dt` of variance per sample and
gains the bias information of the sample that leaves the window. ``mhe`` is the
:class:`~wheelload.estimators.mhe.estimator.MovingHorizonEstimator` whose settings are
extended (its ``window_qp``, ``check``, bias scales and bases).

Example
-------
>>> state, report = advance_extended(mhe, state, terms, arrival)
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from wheelload.estimators.mhe.qp import SOLVED, UNSOLVED, finite_data, prior_solution
from wheelload.estimators.mhe.state import MheState, SampleTerms, shift
from wheelload.estimators.mhe.terms import LOAD_SCALE
from wheelload.estimators.mhe.window import TRAVEL_UNIT, WindowSample


def initial_extended(mhe, x0: np.ndarray) -> dict:
    """The extended window's inert samples, warm start and bias prior."""
    qp, w = mhe.window_qp, mhe.width
    inert = WindowSample(
        z=x0, Jd=np.zeros((4, 4)), b=np.zeros(3),
        Ba=np.zeros((3, len(mhe.acceleration_columns))), ls=np.zeros(4),
        lc=np.zeros(3), xp=np.zeros(4), link=0.0, lower=np.zeros(w), upper=np.zeros(w),
    )  # fmt: skip
    return dict(
        samples=(inert,) * mhe.settings.horizon,
        local=(qp.local_terms(inert),) * mhe.settings.horizon,
        x=np.zeros(qp.n),
        y=np.zeros(qp.n),
        beta=np.zeros(mhe.beta_std.size),
        beta_info=np.diag(1.0 / mhe.beta_std**2),
    )


def advance_extended(mhe, state: MheState, terms: SampleTerms, arrival: np.ndarray):
    """:meth:`MovingHorizonEstimator._advance` for the window with robust losses and bias states."""
    start = time.perf_counter()
    qp, N, w, c = mhe.window_qp, mhe.settings.horizon, mhe.width, state.cost
    z, Jd, Ba, ls, lc = terms.rows
    link = terms.link if state.k > 0 else 0.0
    sample = WindowSample(
        z=z, Jd=Jd, b=terms.b, Ba=Ba[:, mhe.acceleration_columns], ls=ls, lc=lc, xp=terms.xp,
        link=link / (c * LOAD_SCALE**2), lower=terms.lower, upper=terms.upper,
    )  # fmt: skip
    samples = state.samples[1:] + (sample,)
    local = state.local[1:] + (qp.local_terms(sample),)
    arrivals = shift(state.arrival, arrival)
    kfx = shift(state.kfx, terms.kf.x)
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
        # no data in the window: hold, as in the plain window (MovingHorizonEstimator._advance)
        loads = x_warm[: N * width].reshape(N, width)[:, :w].ravel()
        window = dict(arrival=arrivals, xp=np.array([s.xp for s in samples]),
                      lower=np.array([s.lower for s in samples]),
                      upper=np.array([s.upper for s in samples]))  # fmt: skip
        loads = prior_solution(window, j0, state.history[-1], mhe.null, mhe.hard, loads, w)
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
        low, high = qp.bounds(samples, j0, mhe.beta_bound)  # fmt: skip
        if finite_data(Px, g, low, high):
            status, iterations, x_new, y_new = qp.solve_raw(Px, g, low, high, x_warm, y_warm)
        else:
            status, iterations = UNSOLVED, 0
        if status == SOLVED:
            x_warm, y_warm = np.array(x_new), np.array(y_new)
    state = replace(state, samples=samples, local=local, x=x_warm, y=y_warm, kfx=kfx)
    if status == SOLVED:
        x = mhe.check.checked(x_warm[qp.y(N - 1)], sample.lower, sample.upper, sample.xp)
    failed = x is None
    if failed:
        x = mhe.check.fallback(terms.kf.x, state.history[-1])
    else:
        beta = np.clip(x_warm[qp.beta], -mhe.beta_bound, mhe.beta_bound)
        if state.k >= N - 1 and beta.size:  # the oldest sample leaves the window next
            info = info + leaving_information(mhe, state, x_warm)
    if beta.size:
        dt = 1.0 / (mhe.process_noise_density * max(sample.link, 1e-300)) if sample.link else 0.0
        info = np.linalg.inv(np.linalg.inv(info) + np.diag(mhe.beta_density * dt))
    state = replace(
        state,
        k=state.k + 1,
        kf=terms.kf,
        history=shift(state.history, x),
        rho=state.rho,
        arrival=arrivals,
        beta=beta,
        beta_info=0.5 * (info + info.T),
    )
    lag = mhe.settings.lag
    lagged = x if lag == 0 or failed else mhe.window_loads(state, N - 1 - lag)
    report = (lagged, terms, status, iterations, failed, time.perf_counter() - start,
              mhe.bias_report(beta))  # fmt: skip
    return state, report


def leaving_information(mhe, state: MheState, v: np.ndarray) -> np.ndarray:
    """Bias information of the window's oldest sample at the solution ``v``."""
    qp = mhe.window_qp
    s = state.samples[0]
    y = v[qp.y(0)]
    beta = v[qp.beta]
    x = s.xp + qp.X @ y
    nd = qp.travel_basis.shape[1]
    delta = qp.travel_basis @ beta[:nd] * TRAVEL_UNIT if nd else np.zeros(4)
    beta_a = beta[nd:]
    rho_s = s.ls * (s.z - (s.Jd @ delta) - x)
    rho_c = s.lc * (s.b - s.Ba @ beta_a - mhe.A @ x)
    return qp.bias_information(s, rho_s, rho_c)
