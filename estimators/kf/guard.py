r"""Guards of the filter step: plausibility, innovation gate, covariance limits, fault monitor.

Everything here builds CasADi expressions inside the symbolic filter step
(:func:`wheelload.estimators.kf.step.step_expressions`), so the Python
step, the compiled loop and the generated C share one implementation.

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
- **State limit**: an update that would take a load beyond
  :math:`\pm` ``load_limit`` :math:`m g` (or make it non-finite) is not taken;
  the sample is a prediction.
- **Innovation gate** (per update row): the row is skipped when
  :math:`y^2 > \gamma S` (normalised innovation squared, :math:`\chi^2_1`),
  unless the row has been rejected for ``gate_release_time`` in a row: then
  it is taken (no lock-out after a real step change or a long gap).
- **Covariance limits**: the diagonal of :math:`P` is kept within
  :math:`[\sigma_{floor}^2, (m g)^2]`; the ceiling scales row and column
  (:math:`D P D`, positive semidefinite preserved), the floor adds to the
  diagonal.
- **Fault monitor** (detection and isolation, carried as state ``m``): a
  travel channel that does not change for ``stuck_time`` while ``stuck_corners``
  other corners move is *stuck*; the parity residual :math:`r = b - A z` of the raw
  suspension loads (every model term the inputs allow, :func:`parity_model`),
  low-pass filtered, is matched against the signature of
  each channel (a travel fault :math:`f` in corner :math:`i` gives
  :math:`r = -A (\partial z / \partial d_i) f`, through the anti-roll bar
  also in the other wheel of the axle; an accelerometer bias :math:`g`
  gives :math:`r = (\partial b / \partial a) g`), and a channel is isolated when
  its signature explains ``isolation_fraction`` of the residual energy and
  its estimated fault exceeds the limit (at least ``parity_spread_factor`` times
  the fault the residual's own spread looks like, :func:`parity_spread`) for
  ``fault_confirm_time``
  (generalised likelihood ratio, Gertler, *Fault Detection and Diagnosis in
  Engineering Systems*, 1998, ch. 5). An isolated channel is dropped from
  the updates until it has been clean for ``fault_clear_time``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import SimpleNamespace

import casadi as ca

from wheelload.models import GRAVITY, ModelParameters, Vehicle, gates_function
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    INPUTS,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
    input_index,
)

#: Largest plausible hub (unsprung mass) specific force [m/s^2]: 50 g.
MAX_HUB_ACCELERATION = 50.0 * GRAVITY

#: Channels the fault monitor can isolate, in its output order.
FAULT_CHANNELS = ("d_fl", "d_fr", "d_rl", "d_rr", "ax", "ay", "az")


@dataclass(frozen=True, kw_only=True)
class GuardSettings:
    """Thresholds of the guards (all > 0); defaults tested on the bundled scenarios."""

    innovation_gate: float = 9.0  # chi^2_1 threshold on y^2 / S (3 sigma)
    gate_release_time: float = 0.005  # s failing the gate after which a row is taken
    spread_time_constant: float = 1.0  # s, memory of each row's innovation spread
    max_acceleration: float = 3.0  # g, |ax|, |ay|, |az|
    max_speed: float = 120.0  # m/s, |vx|
    max_travel_rate: float = 5.0  # m/s, |v|
    travel_range: float = 1.0  # |d| <= travel_range * m g / k: spring force of the whole weight
    covariance_floor: float = 1.0  # N, smallest standard deviation kept
    stuck_time: float = 0.25  # s without change while another corner moves
    stuck_motion: float = 1.5e-4  # m another corner must move within stuck_time (4 LSB, 12 bit)
    stuck_time_still: float = 0.5  # s without change while another corner only flickers
    parity_time_constant: float = 1.0  # s, low-pass of the parity residual
    travel_fault: float = 0.005  # m, smallest travel-sensor fault isolated
    ax_fault: float = 1.2  # m/s^2, smallest ax fault isolated
    ay_fault: float = 0.3  # m/s^2, smallest ay fault isolated
    az_fault: float = 1.2  # m/s^2, smallest az fault isolated
    isolation_fraction: float = 0.9  # share of residual energy one channel must explain
    fault_confirm_time: float = 0.2  # s a parity fault must persist
    fault_clear_time: float = 1.0  # s clean before an isolated channel is taken back
    # S in the gate and the spread's clip times this: ``wheelload tune`` scales the noise
    # densities by c and the file's [filter] gate_scale = 1/c lands here, so the gate and
    # the spread see the S they had and make the same decisions.
    innovation_variance_scale: float = 1.0
    # The model's own parity spread: a fault is isolated only beyond max(limit, factor * the
    # fault the clean residual of the last parity_spread_time would look like).
    parity_spread_time: float = 30.0  # s, memory of the parity residual's mean square
    parity_spread_factor: float = 2.0  # times the residual's spread, in fault units
    stuck_corners: float = 2.0  # other corners that must move for a still one to be stuck
    # Body rates and their derivatives. On the plant's scenarios (both bundled vehicles,
    # roughness D included, 100 Hz) |w| <= 0.87 rad/s, |dw|/dt <= 17 rad/s^2 between
    # samples and the 20 Hz differentiator's |w_dot| <= 16.6 rad/s^2: the limits leave a
    # factor of about 4 and 2.4 (``wheelload bench hostile --ranges`` measures them).
    max_body_rate: float = 4.0  # rad/s, |wx|, |wy|, |wz|
    max_angular_acceleration: float = 40.0  # rad/s^2, |w_dot| and |dw| / elapsed time
    rate_settle_time: float = 0.1  # s a derivative is not taken after its rate was gated
    hold_time: float = 0.15  # s a term holds a missing or gated input's last valid value
    load_limit: float = 3.0  # m g, largest |Fz| an update may reach
    total_margin: float = 0.25  # m g the total load may pass the log's own vertical-row range

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            number = isinstance(value, int | float) and not isinstance(value, bool)
            if not (number and 0.0 < value < float("inf")):
                raise ValueError(f"guard setting {field.name} must be > 0 and finite, got {value}")
        if self.isolation_fraction >= 1.0:
            raise ValueError("guard setting isolation_fraction must be below 1")

    @staticmethod
    def names() -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(GuardSettings))

    def vector(self) -> list[float]:
        return [float(getattr(self, name)) for name in self.names()]


#: The default thresholds.
DEFAULT_GUARD = GuardSettings()

#: Guards out of reach: the filter as it was before the guards.
GUARDS_OFF = GuardSettings(
    innovation_gate=1e300,
    gate_release_time=1e300,
    spread_time_constant=1.0,
    max_acceleration=1e300,
    max_speed=1e300,
    max_travel_rate=1e300,
    travel_range=1e300,
    covariance_floor=1e-12,
    stuck_time=1e300,
    stuck_time_still=1e300,
    travel_fault=1e300,
    ax_fault=1e300,
    ay_fault=1e300,
    az_fault=1e300,
    max_body_rate=1e300,
    max_angular_acceleration=1e300,
    rate_settle_time=1e-300,
    hold_time=1e-300,
    load_limit=1e300,
    total_margin=1e300,
)


def guard_settings_for(vehicle: Vehicle, base: GuardSettings = DEFAULT_GUARD) -> GuardSettings:
    """``base`` with the fault limits of the vehicle file's ``[filter.faults]``.

    A model that explains less of a vehicle's motion (a larger parity residual on
    clean logs) needs larger limits, or clean driving is isolated as a fault.
    """
    limits = vehicle.filter.faults
    return dataclasses.replace(
        base,
        travel_fault=limits.travel_fault,
        ax_fault=limits.ax_fault,
        ay_fault=limits.ay_fault,
        az_fault=limits.az_fault,
    )


def unpack(vector: ca.SX) -> SimpleNamespace:
    """The settings as symbols, by name, from the guard part of the tuning vector."""
    return SimpleNamespace(**{name: vector[k] for k, name in enumerate(GuardSettings.names())})


# Layout of the monitor state ``m``.
_D_PREV, _FROZEN, _RBAR = slice(0, 4), slice(4, 8), slice(8, 11)
_PERSIST, _CLEAR, _FAULT, _REJECT = slice(11, 18), slice(18, 25), slice(25, 32), slice(32, 39)
_SPREAD, _ANCHOR, _MOVED, _JUMP = slice(39, 46), slice(46, 50), slice(50, 54), slice(54, 58)
_PARITY_MEAN, _PARITY_VARIANCE, _PARITY_WEIGHT = slice(58, 61), slice(61, 64), slice(64, 65)
#: Slots of the fault monitor proper; the held inputs follow (:func:`hold_inputs`).
_MONITOR_END = 65
# Each input's last valid value, its remaining hold time, and each rate derivative's
# remaining settle time after a gated rate.
_HELD = slice(_MONITOR_END, _MONITOR_END + len(INPUTS))
_CREDIT = slice(_HELD.stop, _HELD.stop + len(INPUTS))
_SETTLE = slice(_CREDIT.stop, _CREDIT.stop + len(BODY_RATES))
# Lowest and highest vertical-row b seen so far, less the weight (0 at the start).
_TOTAL = slice(_SETTLE.stop, _SETTLE.stop + 2)
MONITOR_SIZE = _TOTAL.stop
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
    held, credit, settle = m[_HELD], m[_CREDIT], m[_SETTLE]
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
    value, credit = m[_HELD], m[_CREDIT]
    left = credit - dt
    held = (1 - valid) * (left > 0)
    u_term = ca.vertcat(*[ca.if_else(held[k], value[k], u[k]) for k in range(len(INPUTS))])
    valid_term = ca.fmax(valid, held)
    value_next = ca.vertcat(*[ca.if_else(valid[k], u[k], value[k]) for k in range(len(INPUTS))])
    credit_next = ca.vertcat(
        *[ca.if_else(valid[k], g.hold_time, ca.fmax(left[k], 0)) for k in range(len(INPUTS))]
    )
    return u_term, valid_term, held, ca.vertcat(value_next, credit_next)


def with_hold_state(m_next: ca.SX, hold_state: ca.SX, settle: ca.SX, total: ca.SX) -> ca.SX:
    """The fault monitor's next state, then the held inputs, settle times and total range."""
    return ca.vertcat(m_next[0:_MONITOR_END], hold_state, settle, total)


def total_range(m, b_vertical, available, weight) -> ca.SX:
    r"""The range of the vertical row's :math:`b` over the log so far, less the weight.

    ``available``: 1 where this sample's vertical row has its inputs. The range
    starts at :math:`[m g, m g]` (the state starts at the static loads).
    """
    low, high = m[_TOTAL][0], m[_TOTAL][1]
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


#: The [model] switches in the parameter vector: on for the monitor's parity test.
_TERM_SWITCHES = [k for k, name in enumerate(ModelParameters.names()) if name.startswith("term_")]


def parity_model(suspension: ca.Function, equilibrium: ca.Function, u, valid, p):
    r"""``(z, A, b, signatures)`` of the parity test, with every model term switched on.

    The monitor checks the travels and the IMU against the vehicle's complete physics
    (each term whose inputs are valid in the sample), whatever the vehicle file's
    ``[model]`` switches choose for the estimator's updates: a model without the link
    or road-frame terms (the paper's) leaves a parity residual of several hundred N
    on a clean lap, which the signatures of the travel faults explain. ``u``: the
    sanitised inputs, ``valid`` their validity, ``p`` the parameter vector.

    Signatures in the parity space from the models' Jacobians: a travel fault moves
    :math:`b - A z` by :math:`-A\,\partial z / \partial d`, an accelerometer fault by
    :math:`\partial b / \partial a`.
    """
    p = ca.vertcat(*[1 if k in _TERM_SWITCHES else p[k] for k in range(p.shape[0])])
    gates, _ = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    travel, acc = input_index(TRAVEL), input_index(SPECIFIC_FORCE)
    d_sym, acc_sym = ca.SX.sym("d", 4), ca.SX.sym("acc", 3)
    u_d = with_entries(u, travel, d_sym)
    u_acc = with_entries(u, acc, acc_sym)
    d_now = ca.vertcat(*[u[k] for k in travel])
    acc_now = ca.vertcat(*[u[k] for k in acc])
    Jd = ca.substitute(ca.jacobian(suspension(u_d, gates, p), d_sym), d_sym, d_now)
    B = ca.substitute(ca.jacobian(equilibrium(u_acc, gates, p)[1], acc_sym), acc_sym, acc_now)
    return z, A, b, ca.horzcat(-ca.mtimes(A, Jd), B)


def with_entries(u: ca.SX, index: list[int], values: ca.SX) -> ca.SX:
    """``u`` with the entries at ``index`` replaced by ``values``."""
    entries = [u[k] for k in range(u.shape[0])]
    for j, k in enumerate(index):
        entries[k] = values[j]
    return ca.vertcat(*entries)


@dataclass(frozen=True)
class MonitorOutput:
    """Symbolic results of :func:`monitor`."""

    m_next: ca.SX  # next monitor state
    channel_ok: ca.SX  # (7,) 0 for an isolated channel (FAULT_CHANNELS order)
    statistic: ca.SX  # (7,) test statistic, >= 1 where the channel's test fires
    fault: ca.SX  # (7,) 1 while a channel is isolated
    jump: ca.SX  # (4,) 1 while a travel that jumped faster than max_travel_rate is frozen


def monitor(m, u, valid, z, A, b, signatures, dt, r_c, g: GuardSettings) -> MonitorOutput:
    r"""One sample of the fault monitor (see module docstring).

    ``valid`` (:data:`~wheelload.models.INPUTS`): inputs finite and plausible;
    ``z`` (4) raw suspension loads; ``A``, ``b`` the equilibrium (:func:`parity_model`);
    ``signatures`` (3 x 7): the change
    of :math:`b - A z` per unit fault of each channel, :math:`-A\,\partial
    z / \partial d` for the travels [per m] and :math:`\partial b /
    \partial a` for the accelerometer [per m/s^2]; ``dt`` 0 for a rejected
    step; ``r_c`` the constraint noise densities (the residual metric
    :math:`W = \mathrm{diag}(1/r_c)`).
    """
    d = ca.vertcat(*[u[INPUTS.index(name)] for name in TRAVEL])
    d_prev, frozen, rbar = m[_D_PREV], m[_FROZEN], m[_RBAR]
    persist, clear, fault = m[_PERSIST], m[_CLEAR], m[_FAULT]
    # Stuck / dead travel channels: no change at all while another corner moves.
    d_valid = [valid[INPUTS.index(name)] * (dt > 0) for name in TRAVEL]
    changed = [d_valid[i] * (d[i] != d_prev[i]) for i in range(4)]
    frozen_next = ca.vertcat(
        *[ca.if_else(changed[i], 0, frozen[i] + d_valid[i] * dt) for i in range(4)]
    )
    d_prev_next = ca.vertcat(*[ca.if_else(d_valid[i], d[i], d_prev[i]) for i in range(4)])
    # A corner "moves" when its travel leaves +-stuck_motion of its anchor (then re-anchored):
    # a quantised sensor on a still body flickers by a step or two, which is no evidence.
    anchor, moved = m[_ANCHOR], m[_MOVED]
    far = [d_valid[i] * (ca.fabs(d[i] - anchor[i]) > g.stuck_motion) for i in range(4)]
    anchor_next = ca.vertcat(*[ca.if_else(far[i], d[i], anchor[i]) for i in range(4)])
    moved_next = ca.vertcat(*[ca.if_else(far[i], 0, moved[i] + dt) for i in range(4)])
    # A reading that jumped faster than max_travel_rate (a dead sensor falling to its rail)
    # and has not changed since is dropped at once, and is stuck after stuck_time even
    # when the body is still.
    jump = [
        ca.if_else(changed[i], ca.fabs(d[i] - d_prev[i]) > g.max_travel_rate * dt, m[_JUMP][i])
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
    # W = diag(1/r_c) up to a scale (the tests are scale-free): the products of the
    # other two densities, so that no division is repeated at every use.
    w = ca.vertcat(r_c[1] * r_c[2], r_c[0] * r_c[2], r_c[0] * r_c[1])
    energy = ca.sum1(w * rbar_next * rbar_next)
    spread, *spread_next = parity_spread(m, rbar_next, all_valid * dt, m[_FAULT], g)
    limits = [g.travel_fault] * 4 + [g.ax_fault, g.ay_fault, g.az_fault]
    inverse_stuck_time = 1 / g.stuck_time
    statistic, active, persist_next, clear_next, fault_next = [], [], [], [], []
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
        floor_j = ca.sqrt(ca.sum1(w * w * s * s * spread)) * inverse_norm
        limit_j = ca.fmax(limits[j], g.parity_spread_factor * floor_j)
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
    m_next = ca.vertcat(
        d_prev_next,
        frozen_next,
        rbar_next,
        *persist_next,
        *clear_next,
        *fault_next,
        m[_REJECT],
        m[_SPREAD],
        anchor_next,
        moved_next,
        *jump,
        *spread_next,
    )
    return MonitorOutput(
        m_next,
        ca.vertcat(*active),
        ca.vertcat(*statistic),
        ca.vertcat(*fault_next),
        ca.vertcat(*jump),
    )


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
    mean, variance, weight = m[_PARITY_MEAN], m[_PARITY_VARIANCE], m[_PARITY_WEIGHT]
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


def gate_rows(m_reject, m_spread, g: GuardSettings, prior=(0, 0, 0)):
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
    ``gate_release_time`` of failing.
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
                other_group = ca.logic_or(other_group, 1 - record[k][0])
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


def with_gate_state(m_next: ca.SX, times: ca.SX, spread: ca.SX) -> ca.SX:
    """The monitor state with the rows' rejection times and innovation spreads replaced."""
    return ca.vertcat(m_next[0 : _REJECT.start], times, spread, m_next[_SPREAD.stop :])


def reject_slice() -> slice:
    """Where the rows' consecutive rejection times sit in the monitor state."""
    return _REJECT


def spread_slice() -> slice:
    """Where the rows' innovation spreads sit in the monitor state."""
    return _SPREAD
