r"""The filter step's innovation gate, per update row.

The row is skipped when :math:`y^2 > \gamma S` (normalised innovation squared,
:math:`\chi^2_1`), unless the row has been rejected for ``gate_release_time`` in a row: then
it is taken (no lock-out after a real step change or a long gap). Its memory (each row's
rejection time and innovation spread) is carried in the monitor state
(:mod:`.monitor_state`).

Example
-------
>>> y, S = prior_innovations(x_pred, P_pred, z, b, A, r_s, r_c)
>>> prior = prior_failures(y, S, available, m[SPREAD], settings)
>>> gate, record = gate_rows(m[REJECT], m[SPREAD], settings, prior)
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.guards.settings import GuardSettings


def prior_innovations(x, P, z, b, A, r_s, r_c):
    r"""Each row's innovation and its variance against the predicted state ``x, P``,
    before any update of the sample (the seven rows of eq. 20-25 at once):

    .. math:: y = \begin{pmatrix} z \\ b \end{pmatrix} - H x, \quad
              S_{ii} = h_i P h_i^\top + r_i, \quad
              H = \begin{pmatrix} I \\ A \end{pmatrix}, \quad r = (r_s, r_c)
    """
    H = ca.vertcat(ca.DM.eye(4), A)
    y = ca.vertcat(z, b) - ca.mtimes(H, x)
    S = ca.vertcat(*[ca.mtimes(ca.mtimes(H[i, :], P), H[i, :].T) for i in range(7)])
    return y, S + ca.vertcat(r_s, r_c)


def prior_failures(y, S, available, m_spread, g: GuardSettings):
    r"""Which groups of rows fail the gate against the predicted state.

    ``y``, ``S`` (7): each row's innovation against the predicted state (before
    any update of the sample). Returns ``(suspension, constraint, count)``: 1
    if a suspension row (an equilibrium row) fails, and how many rows fail.
    A spike or step on one sensor fails one group only (a travel: its
    suspension row and, through the anti-roll bar, its neighbour's; an
    accelerometer axis: its equilibrium row); a real transient the model
    explains moves the suspension and the equilibrium rows together.
    """
    fail = [
        available[i]
        * (
            y[i] * y[i]
            > g.innovation_gate * ca.fmax(S[i] * g.innovation_variance_scale, m_spread[i])
        )
        for i in range(7)
    ]
    suspension, constraint, count = 0, 0, 0
    for i in range(4):
        suspension = ca.logic_or(suspension, fail[i])
    for i in range(4, 7):
        constraint = ca.logic_or(constraint, fail[i])
    for value in fail:
        count = count + value
    return suspension, constraint, count


def gate_rows(m_reject, m_spread, g: GuardSettings, prior=(0, 0, 0), suspension_passes=None):
    r"""The innovation gate ``gate(i, y, S) -> 0 | 1`` and a record of its decisions.

    Row ``i`` passes when :math:`y^2 \le \gamma \max(k S, \bar s_i)` (:math:`k`:
    ``innovation_variance_scale``, 1 unless the tuning was rescaled), with
    :math:`\bar s_i` the row's recent innovation spread (:func:`next_spread`):
    the filter's noise densities are tuned for accuracy, not for consistency,
    so a row whose model error is coloured (a persistent offset, a transient the
    model follows late) would otherwise fail the :math:`\chi^2` test for long
    stretches and be skipped exactly where it carries the most information.
    A failing row is still taken (released) when rows of the other group fail
    too (``prior``, :func:`prior_failures`, or an earlier suspension row of this
    sample), when three rows fail against the prediction, or after
    ``gate_release_time`` of failing. ``suspension_passes`` (4): the suspension rows'
    decisions of this sample where they were taken elsewhere (default: this gate's record).
    """
    record = {}
    suspension_prior, constraint_prior, count_prior = prior

    def gate(i, y, S):
        passes = y * y <= g.innovation_gate * ca.fmax(S * g.innovation_variance_scale, m_spread[i])
        if i < 4:
            other_group = constraint_prior
        else:
            other_group = suspension_prior
            for k in range(4):
                passed = record[k][0] if suspension_passes is None else suspension_passes[k]
                other_group = ca.logic_or(other_group, 1 - passed)
        transient = ca.logic_or(other_group, count_prior >= 3)
        released = ca.logic_or(m_reject[i] >= g.gate_release_time, transient)
        record[i] = (passes, released, y, S)
        return ca.logic_or(passes, released)

    return gate, record


def reject_times(m_reject, record, available, dt) -> ca.SX:
    """Time each row has failed the gate without a pass (0 once it passes or is absent).

    A row taken by the release stays released while it keeps failing
    (hysteresis): a real step change is followed, not sampled every
    ``gate_release_time``.
    """
    times = []
    for i in range(len(record)):
        passes = record[i][0]
        failing = available[i] * (1 - passes)
        times.append(ca.if_else(failing, m_reject[i] + dt, 0))
    return ca.vertcat(*times)


def next_spread(m_spread, record, available, dt, g: GuardSettings) -> ca.SX:
    r"""Each row's innovation spread after this sample.

    .. math:: \bar s \leftarrow \bar s + \alpha\,(\min(y^2, \gamma \max(S, \bar s))
        - \bar s), \quad \alpha = \Delta t / (\tau + \Delta t)

    (an exponentially weighted mean square, clipped at the gate so that one
    outlier raises it by at most :math:`\alpha (\gamma - 1)`; a sustained
    discrepancy raises it geometrically, within a few samples). Held where the
    row is absent.
    """
    alpha = dt / (g.spread_time_constant + dt)
    spread = []
    for i in range(len(record)):
        _, _, y, S = record[i]
        bound = g.innovation_gate * ca.fmax(S * g.innovation_variance_scale, m_spread[i])
        target = ca.fmin(y * y, bound)
        spread.append(m_spread[i] + available[i] * alpha * (target - m_spread[i]))
    return ca.vertcat(*spread)
