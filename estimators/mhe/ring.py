r"""The plain MHE window over a whole log, the per-sample terms laid out as whole-log arrays.

:meth:`MovingHorizonEstimator.run` with quadratic losses and no bias states
advances the window here instead of through a new :class:`MheState` per
sample. :func:`run_ring` lays each per-sample term out as one array over the
initial window and the log (name -> ``(N + n, ...)``), so the window of sample
``i`` is the view ``[i + 1 : i + 1 + N]`` (no copy, no shift), and hands it to
the loop of :mod:`~wheelload.estimators.mhe.window_loop` with the window's own
arithmetic: the hard window's hoisted out of the loop (:func:`run_hard`), the soft
one's (:func:`~wheelload.estimators.mhe.soft_window.run_soft`), the one-sample
window's the per-sample functions themselves (:func:`run_single`). OSQP is driven
through its low-level solver object (``update_data_vec``, ``update_data_mat``,
``warm_start``, ``solve``), skipping the wrapper's result namespace. The numbers are
those of the per-sample state path to the bit (tested).

Example
-------
>>> estimate = MovingHorizonEstimator(vehicle, MheSettings(horizon=20)).run(signals)
"""

from __future__ import annotations

import math

import numpy as np

from wheelload.estimators.mhe.qp import arrival_pull, finite_data, hessian_values, linear_term
from wheelload.estimators.mhe.soft_window import bad_windows, run_soft
from wheelload.estimators.mhe.terms import LOAD_SCALE
from wheelload.estimators.mhe.window_loop import run_window


def run_ring(mhe, state, H, g, link, xp, lower, upper, kf_loads, arrival, record=None):
    """The plain window over a log (see module docstring).

    ``H, g, link, xp, lower, upper`` are the terms Function's outputs per
    sample, ``kf_loads`` the fallback filter's estimates, ``arrival`` the
    arrival weights. Returns ``(loads, status, iterations, fallback,
    solve_time, final)`` with ``final`` the window's last solution for the
    lagged tail: a callable ``final(j) -> loads`` of window sample ``j``.
    ``record``, a list, receives each solved QP's data ``(Px, q, l, u, x, y)``
    (``wheelload bench mhe`` replays them on bare OSQP).
    """
    s = mhe.settings
    N, w = s.horizon, mhe.width
    n = H.shape[0]
    hard, null = mhe.hard, mhe.null
    k0 = state.k
    fields = {  # per sample: name -> (width, shape in the window)
        "H": (w * w, (w, w)), "g": (w, (w,)), "link": (1, ()), "drift": (1, ()),
        "xp": (4, (4,)), "lower": (w, (w,)), "upper": (w, (w,)), "arrival": (16, (4, 4)),
        "data": (1, ()), "nW": (4, (4,)), "nWn": (1, ()),
    }  # fmt: skip
    H = H.reshape(n, w * w)
    links = np.where(np.arange(k0, k0 + n) > 0, link[:, 0], 0.0)
    drifts = np.zeros(n)
    if hard:  # the random walk's pull along the warp vector, as in _advance
        before = np.vstack([state.xp[-1:], xp[:-1]])
        for i in range(n):
            drifts[i] = links[i] / LOAD_SCALE * float(null @ (xp[i] - before[i]))
    parts = {"H": H, "g": g, "link": links[:, None], "drift": drifts[:, None], "xp": xp,
             "lower": lower, "upper": upper, "arrival": arrival.reshape(n, 16),
             "data": H.any(axis=1)[:, None], "nW": np.zeros((n, 4)),
             "nWn": np.zeros((n, 1))}  # fmt: skip
    previous = {"H": state.H.reshape(N, w * w), "g": state.g, "link": state.link[:, None],
             "drift": state.drift[:, None], "xp": state.xp, "lower": state.lower,
             "upper": state.upper, "arrival": state.arrival.reshape(N, 16),
             "data": state.H.reshape(N, -1).any(axis=1)[:, None], "nW": np.zeros((N, 4)),
             "nWn": np.zeros((N, 1))}  # fmt: skip
    if hard:  # n^T W and n^T W n of each arrival weight, as qp.hessian_values/linear_term form them
        for rows_, arrivals in ((parts, arrival), (previous, state.arrival)):
            for j in range(arrivals.shape[0]):
                nW = null @ arrivals[j]
                rows_["nW"][j] = nW
                rows_["nWn"][j, 0] = nW @ null
    whole = {
        name: np.concatenate([previous[name], parts[name]]).reshape(N + n, *shape)
        for name, (_, shape) in fields.items()
    }
    if N > 1:  # the window's arithmetic hoisted out of the loop
        if hard:
            return run_hard(mhe, state, whole, kf_loads, record)
        return run_soft(mhe, state, whole, kf_loads, record)
    return run_single(mhe, state, whole, kf_loads, record)


def run_single(mhe, state, rows: dict, kf_loads, record=None):
    """The window of one sample over a log: its QP formed by
    :func:`~wheelload.estimators.mhe.qp.hessian_values` and
    :func:`~wheelload.estimators.mhe.qp.linear_term` themselves."""
    null, hard, w = mhe.null, mhe.hard, mhe.width

    def form(i, a, j0, prior, Px, q, low, high) -> bool:
        current = {name: values[a : a + 1] for name, values in rows.items()}
        Px[:] = hessian_values(current, j0, null, hard)
        q[:] = linear_term(current, j0, prior, null, hard)
        return not finite_data(Px, q, *(() if low is None else (low, high)))

    lower, upper, xp = rows["lower"], rows["upper"], rows["xp"]

    def newest_loads(x, newest: int):
        return mhe.check.checked(x[-w:], lower[newest], upper[newest], xp[newest])

    return run_window(mhe, state, rows, kf_loads, record, form=form, newest_loads=newest_loads,
                      size=w * (w + 1) // 2)  # fmt: skip


def _hard_loads(
    omega: float, low: float, high: float, xp, null, bounds, eps, limit: float
) -> list | None:
    r""":meth:`.qp.LoadCheck.newest` of the hard window in plain floats (same arithmetic).

    :math:`\omega` clipped to its interval within ten times OSQP's tolerance, then
    :math:`x = \bar x + n\,\omega` clipped to the load bounds within rounding (a
    collapsed interval, ``low == high``: clipped); None beyond ``limit`` or not finite.
    """
    eps_abs, eps_rel = eps
    size = abs(omega)  # min and max of two as conditionals: the same values, NaN included
    tolerance = 10.0 * (eps_abs + eps_rel * (size if size > 1.0 else 1.0))
    if omega < low - tolerance or omega > high + tolerance:
        return None
    omega = low if low > omega else omega
    scaled = (high if high < omega else omega) * LOAD_SCALE
    x = [xp[0] + null[0] * scaled, xp[1] + null[1] * scaled,
         xp[2] + null[2] * scaled, xp[3] + null[3] * scaled]  # fmt: skip
    lowest, highest = bounds
    if low == high:
        below, above = -math.inf, math.inf
    else:  # a NaN load is refused below whatever its tolerance
        largest = max(1.0, abs(x[0]), abs(x[1]), abs(x[2]), abs(x[3]))
        tolerance = 10.0 * (1e-9 + 1e-12 * largest)
        below, above = lowest - tolerance, highest + tolerance
    for j, value in enumerate(x):
        if value < below or value > above or not abs(value) <= limit:
            return None
        value = lowest if lowest > value else value
        x[j] = highest if highest < value else value
    return x


def run_hard(mhe, state, rows: dict, kf_loads, record=None):
    r"""The hard window (one warp variable :math:`\omega` per sample) over a log.

    The same numbers and OSQP calls as :func:`run_ring`'s loop, with the
    window's arithmetic hoisted out of it: every per-sample term is known
    before the loop, so each field is one array over the initial window and
    the log (``rows``: name -> ``(N + n, ...)``) and the window of sample
    ``i`` is the view ``[i + 1 : i + 1 + N]``. The tridiagonal Hessian's
    interior values :math:`H_j + (\ell_j + \ell_{j+1})` and couplings
    :math:`-\ell_j`, and the linear term's interior :math:`(g_j + d_j) -
    d_{j+1}`, are formed once per sample, interleaved in CSC order, so each
    window's ``Px`` and ``q`` are one copy plus their two end values. Bounds
    are clamped to OSQP's infinity once. Only the estimate-dependent prior term
    is computed per sample.
    """
    s = mhe.settings
    N = s.horizon
    n = len(kf_loads)
    H0, L, D, G = rows["H"][:, 0, 0], rows["link"], rows["drift"], rows["g"][:, 0]
    # Px in CSC order: [d_0, -l_1, d_1, ..., -l_{N-1}, d_{N-1}] = interleaved (-l_j, d_j)[1:]
    interleaved = np.empty((N + n, 2))
    interleaved[:, 0] = -L
    interleaved[:-1, 1] = H0[:-1] + (L[:-1] + L[1:])
    interleaved[-1, 1] = 0.0  # the log's newest sample is always last in its window
    interleaved = interleaved.ravel()
    interior = np.empty(N + n)
    interior[:-1] = (G[:-1] + D[:-1]) - D[1:]
    interior[-1] = 0.0
    # a window's end values once its arrival weight is on its oldest sample (j0 = 0)
    first_px = ((H0[:-1] + (0.0 + L[1:])) + rows["nWn"][:-1]).tolist()
    last_px = (H0 + L).tolist()
    first_q, last_q = (G[:-1] - D[1:]).tolist(), (G + D).tolist()
    bounded = state.y.size > 0
    finite = np.isfinite
    bad = bad_windows(
        ~(finite(H0) & finite(G)),
        ~(finite(L) & finite(D)),
        ~(finite(rows["nWn"]) & finite(rows["nW"]).all(axis=1) & finite(rows["xp"]).all(axis=1)),
        (rows["lower"], rows["upper"]) if bounded else None,
        N,
    ).tolist()  # each window's Px and q: H, g of its samples, links and drifts after its
    # oldest, the arrival weight's n^T W and n^T W n and the xp of its oldest
    H0l, Ll, Dl, Gl = H0.tolist(), L.tolist(), D.tolist(), G.tolist()
    lower_list = rows["lower"][:, 0].tolist()
    upper_list = rows["upper"][:, 0].tolist()
    xp_list = rows["xp"].tolist()
    nW, nWn = rows["nW"].tolist(), rows["nWn"].tolist()
    null = mhe.null.tolist()
    bounds, eps = mhe.load_bounds, (s.solver.eps_abs, s.solver.eps_rel)

    def form(i, a, j0, prior, Px, q, low, high) -> bool:
        newest = a + N - 1
        Px[:] = interleaved[2 * a + 1 : 2 * a + 2 * N]
        q[:] = interior[a : a + N]
        if j0 == 0:
            Px[0], Px[-1] = first_px[a], last_px[newest]
            q[0], q[-1] = first_q[a], last_q[newest]
        else:  # the log's first samples: inert samples before j0
            Px[0] = H0l[a] + (0.0 + Ll[a + 1])
            Px[-1] = H0l[newest] + Ll[newest]
            Px[2 * j0] += nWn[a + j0]
            q[0] = Gl[a] - Dl[a + 1]
            q[-1] = Gl[newest] + Dl[newest]
        q[j0] += arrival_pull(nW[a + j0], xp_list[a + j0], prior.tolist())
        return bad[i] if j0 == 0 else not finite_data(Px, q, *(() if low is None else (low, high)))

    def newest_loads(x, newest: int) -> list | None:
        return _hard_loads(float(x[-1]), lower_list[newest], upper_list[newest], xp_list[newest],
                           null, bounds, eps, mhe.load_limit)  # fmt: skip

    return run_window(mhe, state, rows, kf_loads, record, form=form, newest_loads=newest_loads,
                      size=2 * N - 1)  # fmt: skip
