r"""Input guards of the filter step: plausibility, rate consistency, held inputs.

- **Plausibility** (input ranges from the vehicle): :math:`|a| \le a_{max}`,
  :math:`|v_x| \le v_{max}`, :math:`|d_i| \le c\,m g / k_i` (``c = 1``: the
  travel whose spring force would carry the whole vehicle), :math:`|\dot d_i| \le \dot
  d_{max}`, body rates :math:`|\omega| \le \omega_{max}` and their derivatives
  :math:`|\dot\omega| \le \dot\omega_{max}`, hub accelerations. An implausible
  input is treated as missing.
- **Rate consistency** (:func:`rate_consistency`): a body rate that moves
  from its last valid value by more than :math:`\dot\omega_{max}` times the
  time since is a spike; a rate derivative is not taken while its rate or
  itself was implausible within ``rate_settle_time`` (the first-order
  differentiator that derives it from the rates carries a spike that long).
- **Held inputs** (:func:`hold_inputs`): a model term whose input is missing or
  implausible uses that input's last valid value for up to ``hold_time``;
  the update rows that need the input directly are still skipped.

Example
-------
>>> in_range = plausible_for(u, p, unpack(tuning[GUARD_TUNING]))
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.guards.monitor_state import CREDIT, HELD, SETTLE
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.models import GRAVITY, ModelParameters
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    INPUTS,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
)

#: Largest plausible hub (unsprung mass) specific force [m/s^2]: 50 g.
MAX_HUB_ACCELERATION = 50.0 * GRAVITY
_RATE_INDEX = [INPUTS.index(name) for name in BODY_RATES]
_RATE_DOT_INDEX = [INPUTS.index(name) for name in BODY_RATE_DERIVATIVES]


def plausible_for(u: ca.SX, p: ca.SX, g: GuardSettings) -> ca.SX:
    """:func:`plausible` with the mass and springs read from the parameter vector ``p``
    (:class:`~wheelload.models.ModelParameters` order)."""
    index = {name: k for k, name in enumerate(ModelParameters.names())}
    return plausible(u, p[index["mass"]], p[index["spring_front"]], p[index["spring_rear"]], g)


def plausible(u: ca.SX, mass, spring_front, spring_rear, g: GuardSettings) -> ca.SX:
    r"""1 per input of ``u`` (:data:`~wheelload.models.INPUTS` order) in range.

    Travels, travel rates, the IMU's specific force and ``vx`` from the settings;
    hub accelerations :math:`|a_{hub}| \le` :data:`MAX_HUB_ACCELERATION`; body
    rates :math:`|\omega| \le` ``max_body_rate``, their derivatives
    :math:`|\dot\omega| \le` ``max_angular_acceleration``.
    """
    weight = mass * GRAVITY
    springs = [spring_front, spring_front, spring_rear, spring_rear]
    ok = [1] * len(INPUTS)
    for i, name in enumerate(TRAVEL):
        ok[INPUTS.index(name)] = ca.fabs(u[INPUTS.index(name)]) * springs[i] <= (
            g.travel_range * weight
        )
    for name in TRAVEL_RATE:
        ok[INPUTS.index(name)] = ca.fabs(u[INPUTS.index(name)]) <= g.max_travel_rate
    for name in SPECIFIC_FORCE:
        ok[INPUTS.index(name)] = ca.fabs(u[INPUTS.index(name)]) <= g.max_acceleration * GRAVITY
    ok[INPUTS.index("vx")] = ca.fabs(u[INPUTS.index("vx")]) <= g.max_speed
    for name in HUB_ACCELERATION:
        ok[INPUTS.index(name)] = ca.fabs(u[INPUTS.index(name)]) <= MAX_HUB_ACCELERATION
    for k in _RATE_INDEX:
        ok[k] = ca.fabs(u[k]) <= g.max_body_rate
    for k in _RATE_DOT_INDEX:
        ok[k] = ca.fabs(u[k]) <= g.max_angular_acceleration
    return ca.vertcat(*ok)


def rate_consistency(u, finite, in_range, m, dt, g: GuardSettings) -> tuple[ca.SX, ca.SX]:
    r"""Per input 0 where a body rate or its derivative is inconsistent; the next settle times.

    A rate :math:`\omega_k` whose last valid value :math:`\omega_h` (held in ``m``,
    :func:`hold_inputs`) is :math:`\tau` old fails when

    .. math:: |\omega_k - \omega_h| > \dot\omega_{max} \tau

    (no body turns faster than that; once the hold has run out there is no
    reference and the rate is taken: a bias step is followed, not locked out).
    Its derivative is not taken while the rate or the derivative itself was
    finite but implausible within ``rate_settle_time`` (the first-order
    differentiator that derives it spreads a spike over its settling time).
    ``finite``: 1 per input where the sample is finite; ``in_range`` from
    :func:`plausible`; ``dt`` 0 for a rejected step.
    """
    ok = [1] * len(INPUTS)
    held, credit, settle = m[HELD], m[CREDIT], m[SETTLE]
    settle_next = []
    for j, (k, k_dot) in enumerate(zip(_RATE_INDEX, _RATE_DOT_INDEX, strict=True)):
        left = credit[k] - dt
        elapsed = g.hold_time - left
        jump = (left > 0) * (ca.fabs(u[k] - held[k]) > g.max_angular_acceleration * elapsed)
        rate_gated = finite[k] * (1 - in_range[k] * (1 - jump))
        dot_gated = finite[k_dot] * (1 - in_range[k_dot])
        after = ca.if_else(ca.logic_or(rate_gated, dot_gated), g.rate_settle_time,
                           ca.fmax(settle[j] - dt, 0))  # fmt: skip
        settle_next.append(after)
        ok[k] = 1 - jump
        ok[k_dot] = after <= 0
    return ca.vertcat(*ok), ca.vertcat(*settle_next)


def hold_inputs(u, valid, m, dt, g: GuardSettings) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    r"""The inputs the model terms take: each valid input, else its last valid value.

    An input missing or gated at this sample keeps the value it had at its last
    valid sample for at most ``hold_time``; after that it is missing and its
    terms are dropped. (The terms' flags, bits 16-19, are set either way: the
    term ran without a live input; ``INPUT_HELD`` tells which.)
    Returns ``(u_term, valid_term, held, hold_state)``:
    ``held`` 1 per input that holds, ``hold_state`` the next values of the held
    values and remaining hold times (``m``'s slots after the fault monitor).
    ``u`` is 0 where not ``valid``; ``dt`` 0 for a rejected step (nothing ages).
    """
    value, credit = m[HELD], m[CREDIT]
    left = credit - dt
    held = (1 - valid) * (left > 0)
    u_term = ca.vertcat(*[ca.if_else(held[k], value[k], u[k]) for k in range(len(INPUTS))])
    valid_term = ca.fmax(valid, held)
    value_next = ca.vertcat(*[ca.if_else(valid[k], u[k], value[k]) for k in range(len(INPUTS))])
    credit_next = ca.vertcat(
        *[ca.if_else(valid[k], g.hold_time, ca.fmax(left[k], 0)) for k in range(len(INPUTS))]
    )
    return u_term, valid_term, held, ca.vertcat(value_next, credit_next)
