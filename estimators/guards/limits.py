r"""State and covariance limits of the filter step.

- **State limit** (:func:`within_load_limit`): an update that would take a load beyond
  :math:`\pm` ``load_limit`` :math:`m g` (or make it non-finite), or carry the total
  further outside the log's own vertical-row range (:func:`total_range`), is not taken;
  the sample is a prediction.
- **Covariance limits**: the diagonal of :math:`P` is kept within
  :math:`[\sigma_{floor}^2, (m g)^2]`; the ceiling scales row and column
  (:math:`D P D`, positive semidefinite preserved), the floor adds to the
  diagonal.

Example
-------
>>> P, limited = limit_covariance(P_pred, settings.covariance_floor, (m * g) ** 2)
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.guards.monitor_state import TOTAL
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.models import GRAVITY


def variance_ceiling(mass):
    r""":math:`(m g)^2` [N^2]: the largest variance of a wheel load, and the first sample's
    prediction (no prior information); ``mass`` numeric or symbolic."""
    weight = mass * GRAVITY
    return weight * weight


def total_range(m, b_vertical, available, weight) -> ca.SX:
    r"""The range of the vertical row's :math:`b` over the log so far, less the weight.

    ``available``: 1 where this sample's vertical row has its inputs. The range
    starts at :math:`[m g, m g]` (the state starts at the static loads).
    """
    low, high = m[TOTAL][0], m[TOTAL][1]
    offset = b_vertical - weight
    return ca.vertcat(
        ca.if_else(available, ca.fmin(low, offset), low),
        ca.if_else(available, ca.fmax(high, offset), high),
    )


def within_load_limit(x: ca.SX, x_prior: ca.SX, total, weight, g: GuardSettings) -> ca.SX:
    r"""1 if an update from ``x_prior`` to ``x`` stays within the physical load envelope.

    Every load finite and within :math:`\pm` ``load_limit`` :math:`m g`, and the
    total :math:`\sum F_z` no further outside the log's own vertical-row range
    ``total`` (:func:`total_range`), widened by ``total_margin`` :math:`m g`, than
    before the update (the vertical row is the equilibrium of the total, eq. 15;
    travels the model cannot explain must not carry the total beyond any
    :math:`m a_z` the log shows).
    """
    ok = 1
    for i in range(x.shape[0]):
        ok = ca.logic_and(ok, ca.fabs(x[i]) <= g.load_limit * weight)
    low = weight + total[0] - g.total_margin * weight
    high = weight + total[1] + g.total_margin * weight

    def excess(value):
        return ca.fmax(ca.fmax(value - high, low - value), 0)

    return ca.logic_and(ok, excess(ca.sum1(x)) <= excess(ca.sum1(x_prior)))


def floor_covariance(P: ca.SX, floor_std) -> tuple[ca.SX, ca.SX]:
    r"""``P`` with its diagonal at least :math:`\sigma_{floor}^2`; and 1 if changed.

    After an update the variances only fall, so the ceiling of the
    prediction still holds; rounding can still take a variance below zero.
    """
    n = P.shape[0]
    floor = floor_std * floor_std
    rows = [
        ca.horzcat(*[ca.fmax(P[i, i], floor) if i == j else P[i, j] for j in range(n)])
        for i in range(n)
    ]
    changed = 0
    for i in range(n):
        changed = ca.logic_or(changed, P[i, i] < floor)
    return ca.vertcat(*rows), changed


def limit_covariance(P: ca.SX, floor_std, ceiling) -> tuple[ca.SX, ca.SX]:
    r"""``P`` with its diagonal in :math:`[\sigma_{floor}^2, \mathrm{ceiling}]`; and 1 if changed.

    Off-diagonal entries are scaled by :math:`s_i s_j`,
    :math:`s_i = \sqrt{\mathrm{ceiling} / P_{ii}}` where the ceiling binds
    (an infinite variance gives :math:`s_i = 0`, never NaN).
    """
    n = P.shape[0]
    floor = floor_std * floor_std
    over = [P[i, i] > ceiling for i in range(n)]
    under = [P[i, i] < floor for i in range(n)]
    scale = [ca.if_else(over[i], ca.sqrt(ceiling / P[i, i]), 1) for i in range(n)]
    rows = []
    for i in range(n):
        row = []
        for j in range(n):
            if i == j:
                row.append(ca.fmin(ca.fmax(P[i, i], floor), ceiling))
            else:
                row.append(P[i, j] * scale[i] * scale[j])
        rows.append(ca.horzcat(*row))
    changed = 0
    for i in range(n):
        changed = ca.logic_or(changed, ca.logic_or(over[i], under[i]))
    return ca.vertcat(*rows), changed
