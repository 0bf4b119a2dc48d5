r"""The filter step's sensor-fault monitor: detection and isolation, carried in ``m``.

A travel channel that does not change for ``stuck_time`` (seconds: each of its samples
adds the time since its last one) while ``stuck_corners`` other corners move is *stuck*;
the parity residual :math:`r = b - A z` of the raw
suspension loads (every model term the inputs allow,
:func:`~wheelload.models.terms.parity_model`),
low-pass filtered, is matched against the signature of
each channel (a travel fault :math:`f` in corner :math:`i` gives
:math:`r = -A (\partial z / \partial d_i) f`, through the anti-roll bar
also in the other wheel of the axle; an accelerometer bias :math:`g`
gives :math:`r = (\partial b / \partial a) g`), and a channel is isolated when
its signature explains ``isolation_fraction`` of the residual energy and
its estimated fault exceeds the limit (at least ``parity_spread_factor`` times
the fault the residual's own spread looks like, :func:`parity_spread`, and the
spread a payload not yet learnt may leave; for an accelerometer axis its fault is the
``bias_share`` of it must not grow with the axis' acceleration, :func:`gain_bias_split`,
since a residual that grows with it is a gain the vehicle file has wrong) for
``fault_confirm_time``
(generalised likelihood ratio, Gertler, *Fault Detection and Diagnosis in
Engineering Systems*, 1998, ch. 5). An isolated channel is dropped from
the updates until it has been clean for ``fault_clear_time``.

Example
-------
>>> watch = monitor(m, u, valid, *parity_model(suspension, equilibrium, u, valid, p), dt, r_c, g)
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from wheelload.estimators.guards.monitor_state import (
    ANCHOR,
    CLEAR,
    CREDIT,
    D_PREV,
    EXCITATION,
    FAULT,
    FROZEN,
    GAIN_SUMS,
    JUMP,
    MOVED,
    PARITY_MEAN,
    PARITY_VARIANCE,
    PARITY_WEIGHT,
    PERSIST,
    RBAR,
    TRAVEL_SEEN,
    UNEXPLAINED,
)
from wheelload.estimators.guards.settings import FAULT_CHANNELS, GuardSettings
from wheelload.models import GRAVITY
from wheelload.models.inputs import (
    INPUTS,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
)


@dataclass(frozen=True)
class MonitorOutput:
    """Symbolic results of :func:`monitor`."""

    m_next: dict  # the fault monitor's fields of the next state (monitor_state.MONITOR), by name
    channel_ok: ca.SX  # (7,) 0 for an isolated channel (FAULT_CHANNELS order)
    statistic: ca.SX  # (7,) test statistic, >= 1 where the channel's test fires
    fault: ca.SX  # (7,) 1 while a channel is isolated
    jump: ca.SX  # (4,) 1 while a travel that jumped faster than max_travel_rate is frozen
    seen: ca.SX  # (4,) 1 once a travel channel has had a valid sample


def monitor(
    m, u, valid, z, A, b, signatures, dt, r_c, g: GuardSettings, unexplained=None
) -> MonitorOutput:
    r"""One sample of the fault monitor (module docstring).

    ``valid`` (:data:`~wheelload.models.INPUTS`): inputs finite and plausible;
    ``z`` (4) raw suspension loads; ``A``, ``b`` the equilibrium
    (:func:`~wheelload.models.terms.parity_model`);
    ``signatures`` (3 x 7): the change
    of :math:`b - A z` per unit fault of each channel, :math:`-A\,\partial
    z / \partial d` for the travels [per m] and :math:`\partial b /
    \partial a` for the accelerometer [per m/s^2]; ``dt`` 0 for a rejected
    step; ``r_c`` the constraint noise densities (the residual metric
    :math:`W = \mathrm{diag}(1/r_c)`); ``unexplained`` (3 x 3, default 0): the covariance
    of the residual that the car's unknown payload may leave,
    :math:`J_\vartheta P_\vartheta J_\vartheta^T` (:mod:`wheelload.estimators.kf.payload`).
    A payload moves the residual like a bias: while it is not yet learnt (a log that
    starts in a turn, a stop where people got in) a channel's fault must stand out of
    that spread too, so a
    changed car is not blamed on a sensor.
    """
    d = ca.vertcat(*[u[INPUTS.index(name)] for name in TRAVEL])
    d_prev, frozen, rbar = m[D_PREV], m[FROZEN], m[RBAR]
    persist, clear, fault = m[PERSIST], m[CLEAR], m[FAULT]
    # Stuck / dead travel channels: no change at all while another corner moves. The time a
    # travel has not changed grows at each of its samples by the time since its last valid
    # value (``since``, below; the row's dt once it has been seen every row): seconds, not
    # rows, when other channels come between travel frames.
    d_valid = [valid[INPUTS.index(name)] * (dt > 0) for name in TRAVEL]
    changed = [d_valid[i] * (d[i] != d_prev[i]) for i in range(4)]
    seen = m[TRAVEL_SEEN]
    credit = m[CREDIT]
    since = [dt + (g.hold_time - credit[INPUTS.index(name)]) for name in TRAVEL]
    frozen_next = ca.vertcat(
        *[
            ca.if_else(changed[i], 0, frozen[i] + d_valid[i] * ca.if_else(seen[i], since[i], dt))
            for i in range(4)
        ]
    )
    d_prev_next = ca.vertcat(*[ca.if_else(d_valid[i], d[i], d_prev[i]) for i in range(4)])
    # A corner "moves" when its travel leaves +-stuck_motion of its anchor (then re-anchored):
    # a quantised sensor on a still body flickers by a step or two, which is no evidence.
    anchor, moved = m[ANCHOR], m[MOVED]
    far = [d_valid[i] * (ca.fabs(d[i] - anchor[i]) > g.stuck_motion) for i in range(4)]
    anchor_next = ca.vertcat(*[ca.if_else(far[i], d[i], anchor[i]) for i in range(4)])
    moved_next = ca.vertcat(*[ca.if_else(far[i], 0, moved[i] + dt) for i in range(4)])
    # A reading that jumped faster than max_travel_rate (a dead sensor falling to its rail)
    # and has not changed since is dropped at once, and is stuck after stuck_time even
    # when the body is still.
    # (A channel's first valid sample has nothing to jump from.) The jump is over the time
    # since the travel's last valid value, dt plus what its hold has used of hold_time
    # (plausibility.hold_inputs; at least hold_time once that has run out): the interval of
    # a travel frame, not of the last row, when other channels come between travel frames.
    jump = [
        ca.if_else(
            changed[i],
            seen[i] * (ca.fabs(d[i] - d_prev[i]) > g.max_travel_rate * since[i]),
            m[JUMP][i],
        )
        for i in range(4)
    ]
    # The body moves for corner i when ``stuck_corners`` other corners moved within
    # stuck_time: one other corner alone (a spike, a bad sample) is no evidence that i
    # should have changed too.
    stuck = []
    for i in range(4):
        movers, others_changing = 0, 0
        for j in range(4):
            if j != i:
                movers = movers + (moved_next[j] < g.stuck_time)
                others_changing = ca.logic_or(others_changing, frozen_next[j] < 0.5 * g.stuck_time)
        others_moving = ca.logic_or(jump[i], movers >= g.stuck_corners)
        moving = ca.logic_and(frozen_next[i] >= g.stuck_time, others_moving)
        still = ca.logic_and(frozen_next[i] >= g.stuck_time_still, others_changing)
        stuck.append(ca.logic_or(moving, still))
    # Parity residual of the raw suspension loads, low-pass filtered.
    all_valid = 1
    for name in TRAVEL + TRAVEL_RATE + SPECIFIC_FORCE + ("vx",):
        all_valid = all_valid * valid[INPUTS.index(name)]
    alpha = all_valid * dt / (g.parity_time_constant + dt)
    r = b - ca.mtimes(A, z)
    rbar_next = rbar + alpha * (r - rbar)
    # The payload's share, low-passed alike: a payload just learnt leaves the old residual
    # in rbar for a time constant, and its spread with it.
    unexplained_next = low_passed_covariance(m[UNEXPLAINED], unexplained, alpha)
    acc = ca.vertcat(*[u[INPUTS.index(name)] for name in SPECIFIC_FORCE])
    excitation = ca.vertcat(acc[0], acc[1], acc[2] - GRAVITY)
    excitation_next = m[EXCITATION] + alpha * (excitation - m[EXCITATION])
    # W = diag(1/r_c) up to a scale (the tests are scale-free): the products of the
    # other two densities, so that no division is repeated at every use.
    w = ca.vertcat(r_c[1] * r_c[2], r_c[0] * r_c[2], r_c[0] * r_c[1])
    energy = ca.sum1(w * rbar_next * rbar_next)
    spread, *spread_next = parity_spread(m, rbar_next, all_valid * dt, m[FAULT], g)
    limits = [g.travel_fault] * 4 + [g.ax_fault, g.ay_fault, g.az_fault]
    inverse_stuck_time = 1 / g.stuck_time
    statistic, active, persist_next, clear_next, fault_next = [], [], [], [], []
    gain_sums_next = []
    for j in range(7):
        s = signatures[:, j]
        norm = ca.sum1(w * s * s)
        projection = ca.sum1(w * s * rbar_next)
        # A channel without signature (norm 0) can never be isolated; no 0/0.
        inverse_norm = 1 / ca.if_else(norm > 0, norm, 1) * (norm > 0)
        magnitude = projection * inverse_norm
        isolated = projection * magnitude > g.isolation_fraction * energy
        # The fault the model's own clean residual would look like on this channel:
        # sqrt(sum (w s)^2 spread) / (s' W s), the spread of the magnitude estimate.
        ws = w * s
        floor_j = (
            ca.sqrt(ca.sum1(ws * ws * spread) + payload_term(ws, unexplained_next)) * inverse_norm
        )
        limit_j = ca.fmax(limits[j], g.parity_spread_factor * floor_j)
        if j >= 4:
            # An axis' fault estimate must be a bias for at least bias_share: the part that
            # does not grow with the acceleration the rest of the car says the axis saw (a
            # gain of the file does, gain_bias_split).
            sums_j, bias = gain_bias_split(
                m[GAIN_SUMS][5 * (j - 4) : 5 * (j - 4) + 5],
                excitation_next[j - 4] - magnitude,
                magnitude,
                all_valid * dt,
                g,
            )
            gain_sums_next.append(sums_j)
            isolated = ca.logic_and(isolated, ca.fabs(bias) >= g.bias_share * ca.fabs(magnitude))
        candidate = ca.logic_and(ca.fabs(magnitude) > limit_j, isolated)
        persist_j = ca.if_else(candidate, persist[j] + all_valid * dt, 0)
        parity_fault = persist_j >= g.fault_confirm_time
        level = ca.fabs(magnitude) / limit_j * isolated
        if j < 4:
            now = ca.logic_or(stuck[j], parity_fault)
            level = ca.fmax(level, frozen_next[j] * inverse_stuck_time * stuck[j])
        else:
            now = parity_fault
        clear_j = ca.if_else(now, 0, clear[j] + dt)
        fault_j = ca.logic_or(now, ca.logic_and(fault[j], clear_j < g.fault_clear_time))
        statistic.append(level)
        persist_next.append(persist_j)
        clear_next.append(clear_j)
        fault_next.append(fault_j)
        active.append((1 - fault_j) * (1 - jump[j]) if j < 4 else 1 - fault_j)
    parity_mean, parity_variance, parity_weight = spread_next
    m_next = {
        "d_prev": d_prev_next,
        "frozen": frozen_next,
        "rbar": rbar_next,
        "persist": ca.vertcat(*persist_next),
        "clear": ca.vertcat(*clear_next),
        "fault": ca.vertcat(*fault_next),
        "anchor": anchor_next,
        "moved": moved_next,
        "jump": ca.vertcat(*jump),
        "parity_mean": parity_mean,
        "parity_variance": parity_variance,
        "parity_weight": parity_weight,
        "unexplained": unexplained_next,
        "excitation": excitation_next,
        "gain_sums": ca.vertcat(*gain_sums_next),
    }
    return MonitorOutput(
        m_next,
        ca.vertcat(*active),
        ca.vertcat(*statistic),
        ca.vertcat(*fault_next),
        ca.vertcat(*jump),
        ca.vertcat(*[ca.logic_or(seen[i], d_valid[i]) for i in range(4)]),
    )


def gain_bias_split(sums, seen, fault, dt, g: GuardSettings):
    r"""The bias part of an accelerometer axis' fault estimate; and the next sums it needs.

    The fault estimate :math:`\hat g` (from the low-passed residual) is fitted as
    :math:`\hat g = b + k\,a` over the last ``gain_time_constant`` (exponentially weighted
    means :math:`\bar 1, \bar a, \overline{a^2}, \bar g, \overline{a g}`), with
    :math:`a` the acceleration the rest of the car says the axis saw (its low-passed reading
    less :math:`\hat g`): a sensor bias is :math:`b`, a gain of the file (bars, springs,
    mass, CG height: the load transfer it scales) is :math:`k`. Both are kept small by
    :math:`\lambda = ` ``gain_ridge`` times :math:`\bar 1 b^2` and
    :math:`\bar 1 a_g^2 k^2`, ``a_g`` = ``gain_acceleration``: where the axis saw less
    than :math:`a_g` the estimate is taken as a bias, in a steady turn above it as a
    gain, and where the acceleration varies the two are told apart.

    .. math:: \begin{bmatrix} \bar 1 (1 + \lambda) & \bar a \\
              \bar a & \overline{a^2} + \lambda \bar 1 a_g^2 \end{bmatrix}
              \begin{bmatrix} b \\ k \end{bmatrix} =
              \begin{bmatrix} \bar g \\ \overline{a g} \end{bmatrix}
    """
    beta = dt / (g.gain_time_constant + dt)
    new = [seen * 0 + 1, seen, seen * seen, fault, seen * fault]
    sums_next = ca.vertcat(*[sums[i] + beta * (new[i] - sums[i]) for i in range(5)])
    one, a, aa, gg, ag = (sums_next[i] for i in range(5))
    ridge = g.gain_ridge
    k_row = aa + ridge * one * g.gain_acceleration**2
    det = one * (1 + ridge) * k_row - a * a
    bias = (gg * k_row - a * ag) / ca.if_else(det > 0, det, 1) * (det > 0)
    return sums_next, bias


_UPPER = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


def low_passed_covariance(previous, covariance, alpha):
    """The upper triangle of a 3 x 3 covariance, low-passed by ``alpha`` (0 without one)."""
    if covariance is None:
        return ca.DM.zeros(len(_UPPER))
    now = ca.vertcat(*[covariance[i, j] for i, j in _UPPER])
    return previous + alpha * (now - previous)


def payload_term(ws, upper):
    """:math:`(W s)^T C (W s)` with ``C`` given by its upper triangle: the payload's share
    of a channel's fault spread."""
    total = 0
    for k, (i, j) in enumerate(_UPPER):
        total = total + (1 if i == j else 2) * ws[i] * upper[k] * ws[j]
    return total


def parity_spread(m, rbar, dt, fault, g: GuardSettings):
    r"""The model's own parity spread per row; and the next monitor slots it needs.

    .. math:: w \leftarrow w + \beta (1 - w), \quad
        \mu \leftarrow \mu + \beta (\bar r - \mu), \quad
        v \leftarrow v + \beta \big((\bar r - \mu / w)^2 - v\big), \quad
        \sigma_r^2 = v / w, \quad \beta = \Delta t / (\tau_q + \Delta t)

    the exponentially weighted variance of the low-passed parity residual
    :math:`\bar r` about its own mean over ``parity_spread_time``
    (:math:`\tau_q`), bias-corrected by the weight :math:`w` (0 at the start, so
    the first samples count in full). It is held while any channel is isolated
    (a fault is not learnt as model mismatch). The variance, not the mean square:
    a steady offset of the model says nothing about how far the residual wanders
    on clean driving. A model that explains less of the motion (the paper's,
    without links or road frame) has a larger spread, hence larger effective fault
    limits (:func:`monitor`). ``dt`` is 0 for a sample whose residual is not updated.

    Returns ``(spread, mean, variance, weight)``: :math:`\sigma_r^2` (3) and the next
    :math:`\mu, v, w`.
    """
    mean, variance, weight = m[PARITY_MEAN], m[PARITY_VARIANCE], m[PARITY_WEIGHT]
    isolated = 0
    for j in range(len(FAULT_CHANNELS)):
        isolated = ca.logic_or(isolated, fault[j])
    beta = (1 - isolated) * dt / (g.parity_spread_time + dt)
    weight_next = weight + beta * (1 - weight)
    inverse_weight = 1 / ca.if_else(weight_next > 0, weight_next, 1)
    mean_next = mean + beta * (rbar - mean)
    deviation = rbar - mean_next * inverse_weight
    variance_next = variance + beta * (deviation * deviation - variance)
    return variance_next * inverse_weight, mean_next, variance_next, weight_next
