r"""One step of the two-stage physics-constrained Kalman filter, as a CasADi Function.

(Siegloff & Choi §III, method A.) State :math:`x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]`,
random walk (eq. 12, 19); first update with the suspension pseudo-measurement
:math:`z = x + v_s` (eq. 13, 20-22); second update with the rigid-body equilibrium as a
soft constraint :math:`b = A x + w_c` (eq. 17, 23-25). Joseph form throughout. The noise
is built from the tuning vector (:mod:`wheelload.estimators.kf.tuning`) and the
input-dependent densities of :mod:`wheelload.models.measurement_noise`; the guards of
:mod:`wheelload.estimators.kf.guard` act on the masks of the updates.

The step is built from the model Functions in ``wheelload.models``, so the Python filter,
the compiled loops and the generated C share one implementation.

Example
-------
>>> step = step_function()  # (x, P, m, u, u_valid, dt, p, tuning) -> (x_next, P_next, ...)
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.kernels.kalman import (
    predict,
    sequential_update,
    sequential_update_innovations,
    upper,
)
from wheelload.estimators.kf import (
    fault_monitor,
    guard,
    innovation_gate,
    limits,
    monitor_state,
    payload,
    plausibility,
    reported_std,
)
from wheelload.estimators.kf.step_cache import STEP_INPUT_NAMES, STEP_NAME, STEP_OUTPUT_NAMES
from wheelload.estimators.kf.tuning import GUARD_TUNING, PAYLOAD_SLICE, SIGMA_TUNING, TUNING
from wheelload.models import (
    GRAVITY,
    INPUTS,
    OPTIONAL_INPUTS,
    ModelParameters,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.input_validity import dependency_mask, interval_is_valid, sanitise
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    SPECIFIC_FORCE,
    TRAVEL,
    TRAVEL_RATE,
    input_index,
)
from wheelload.models.loaded_vehicle import loaded_parameters_function
from wheelload.models.measurement_noise import DENSITIES as NOISE_DENSITY_ORDER
from wheelload.models.measurement_noise import measurement_noise_function
from wheelload.models.roll_split import SPLIT_NOISE_RATIO, roll_split_function
from wheelload.models.terms import parity_model

_P_INDEX = {name: k for k, name in enumerate(ModelParameters.names())}
_TRAVEL_INDEX = input_index(TRAVEL)
_RATE_INDEX = input_index(TRAVEL_RATE)
_ACC_INDEX = input_index(SPECIFIC_FORCE)
_HUB_INDEX = input_index(HUB_ACCELERATION)
_BODY_RATE_INDEX = input_index(BODY_RATES + BODY_RATE_DERIVATIVES)


def _required(valid: ca.SX) -> ca.SX:
    """Validity of the inputs an update cannot do without (optional inputs count as valid)."""
    return ca.vertcat(
        *[1 if name in OPTIONAL_INPUTS else valid[i] for i, name in enumerate(INPUTS)]
    )


def _channel_drop(channel_ok: ca.SX) -> ca.SX:
    """Validity factor per input from the fault monitor's channels (d_fl..d_rr, ax, ay, az).

    A travel channel drops its travel and travel rate; an accelerometer axis drops
    that axis; every other input is kept.
    """
    factors = [1] * len(INPUTS)
    for i in range(4):
        factors[_TRAVEL_INDEX[i]] = channel_ok[i]
        factors[_RATE_INDEX[i]] = channel_ok[i]
    for j in range(3):
        factors[_ACC_INDEX[j]] = channel_ok[4 + j]
    return ca.vertcat(*factors)


def model_rows(suspension: ca.Function, equilibrium: ca.Function, u_raw, valid, p):
    """Pseudo-measurement, equilibrium and their masks from raw inputs and validity.

    Returns ``(z, A, b, mask_s, mask_c, dropped)``. An update needs the inputs
    of the paper's model (every term gated off: the Jacobian sparsity of the
    rows with zero gates); a term whose optional input is missing is gated off
    for the sample instead, and ``dropped`` (``wheelload.models.DROPPABLE``
    order) says which.
    """
    u = sanitise(u_raw, valid)
    z, A, b, dropped = model_equations(suspension, equilibrium, u, valid, p)
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    return z, A, b, mask_s, mask_c, dropped


def model_equations(suspension: ca.Function, equilibrium: ca.Function, u, valid, p):
    """``(z, A, b, dropped)`` from inputs ``u`` (0 where not ``valid``) with their terms gated."""
    gates, dropped = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    return z, A, b, dropped


def row_masks(suspension: ca.Function, equilibrium: ca.Function, u, u_raw, valid, p):
    """``(mask_s, mask_c)``: 1 for each row whose paper-model inputs are all valid."""
    paper = ca.DM.zeros(gates_function().size_out(0))
    mask_s = dependency_mask(suspension(u, paper, p), u_raw, _required(valid))
    mask_c = dependency_mask(equilibrium(u, paper, p)[1], u_raw, _required(valid))
    return mask_s, mask_c


def step_expressions(
    suspension: ca.Function,
    equilibrium: ca.Function,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
):
    """Symbolic inputs and outputs of one filter step built from the model Functions.

    ``measurement_noise(u, u_valid, densities, dt_nominal) -> (R_s, R_c)``
    defaults to :func:`~wheelload.models.measurement_noise.measurement_noise_function`.

    ``constraint_update(x, P, b, A, r_c, mask, gate) -> (x, P, y, S, use)``
    is the second stage; the default is the soft-constraint Kalman update
    (eq. 23-25), one row at a time. Outputs ``innovation`` and
    ``innovation_variance`` (7 each, update order: suspension FL, FR, RL, RR,
    then vertical, pitch, roll) are each row's pre-update innovation and its
    variance S; both are 0 for a row whose inputs are missing. The guards of
    :mod:`wheelload.estimators.kf.guard` (plausibility, innovation gate, fault
    monitor with state ``m``, covariance limits) act on the masks of the
    updates, so a guarded row changes neither x nor P.
    """
    x = ca.SX.sym("x", 4)
    P = ca.SX.sym("P", 4, 4)
    m = ca.SX.sym("m", monitor_state.MONITOR.size)
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid_raw = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    p_file = ca.SX.sym("p", len(ModelParameters.names()))
    tuning = ca.SX.sym("tuning", TUNING.size)
    settings = guard.unpack(tuning[GUARD_TUNING])
    dt_nominal = TUNING.value(tuning, "sample_interval")
    payload_tuning = tuning[PAYLOAD_SLICE]

    # A non-positive or non-finite interval skips the whole step: the state is held.
    dt_ok = interval_is_valid(dt)
    dt_safe = ca.if_else(dt_ok, dt, 1.0)
    dt_used = dt_safe * dt_ok

    # The payload the file does not know (.payload), predicted to this sample: every row
    # below sees the loaded vehicle; the suspension's offsets stay the reference state's.
    theta, P_theta = payload.predict(
        m[monitor_state.PAYLOAD],
        ca.reshape(m[monitor_state.PAYLOAD_COVARIANCE], 4, 4),
        m[monitor_state.STARTED],
        sanitise(u_raw, valid_raw),
        valid_raw,
        dt_used,
        payload_tuning,
    )
    p = loaded_parameters_function()(p_file, payload.applied(theta, payload_tuning))

    # Missing or implausible inputs are replaced by zero and skip the updates they feed;
    # a body rate that jumps, or a derivative after a gated rate, counts as implausible.
    u_finite = sanitise(u_raw, valid_raw)
    in_range = plausibility.plausible_for(u_finite, p, settings)
    consistent, settle_next = plausibility.rate_consistency(
        u_finite, valid_raw, in_range, m, dt_used, settings
    )
    in_range = in_range * consistent
    valid_plausible = valid_raw * in_range
    u = sanitise(u_raw, valid_plausible)
    # The model terms take each missing or gated input's last valid value for
    # ``hold_time``, then drop; the rows needing the input are skipped. ``dropped`` (the
    # flags) marks a term without a live input, held or dropped.
    u_term, valid_term, held, hold_state = plausibility.hold_inputs(
        u, valid_plausible, m, dt_used, settings
    )
    z, A, b, _ = model_equations(suspension, equilibrium, u_term, valid_term, p)
    dropped = gates_function()(valid_plausible, p)[1]

    # Fault monitor: an isolated channel is dropped like a missing one. Its parity test
    # uses every model term the inputs allow (held inputs included), whatever the
    # [model] switches.
    parity = parity_model(suspension, equilibrium, u_term, valid_term, p)
    # The fault monitor's parity test weighs the constant densities (the paper's R_c).
    rc_density = TUNING.value(tuning, "constraint_noise_density")
    # What the payload not yet learnt may leave in the residual (a changed car, no fault).
    gates_term = gates_function()(valid_term, p)[0]
    residual_theta = payload.residual_function(equilibrium)
    unexplained = payload.unexplained(
        theta, P_theta, z, u_term, gates_term, p_file, payload_tuning, residual_theta
    )
    watch = fault_monitor.monitor(
        m, u, valid_plausible, *parity, dt_used, rc_density, settings, unexplained
    )
    valid = valid_plausible * _channel_drop(watch.channel_ok)
    # The updates the channels left after the guards feed (an isolated channel's rows are
    # skipped; the model terms keep their inputs, as for the monitor).
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    mask_s = mask_s * dt_ok
    mask_c = mask_c * dt_ok

    # Measurement noise from the nominal interval: a gap grows P, never shrinks R.
    weight = p[_P_INDEX["mass"]] * GRAVITY
    ceiling = limits.variance_ceiling(p[_P_INDEX["mass"]])
    q = TUNING.value(tuning, "process_noise_density")
    Q = ca.fmin(q * dt_used, ceiling) * ca.DM.eye(4)
    # R_s, R_c from the inputs (models/measurement_noise.py; constant with the default zeros).
    densities = TUNING.values(tuning, NOISE_DENSITY_ORDER)
    noise = measurement_noise or measurement_noise_function()
    rs, rc = noise(u, valid_plausible, densities, dt_nominal)

    # R_s and R_c are diagonal: row-by-row updates equal the joint ones (eq. 20-25).
    reject, spread = m[monitor_state.REJECT], m[monitor_state.SPREAD]
    x_pred, P_pred = predict(x, upper(P), Q)
    P_pred, limited_pred = limits.limit_covariance(P_pred, settings.covariance_floor, ceiling)
    # Start where the car is: the first sample sees no prior information, so its rows set
    # the loads (a log that starts in a turn carries no start-up transient).
    # An invalid interval holds the state, so the start waits for the first valid one.
    started = m[monitor_state.STARTED]
    P_pred = ca.if_else(ca.logic_or(started, 1 - dt_ok), P_pred, ceiling * ca.DM.eye(4))
    y_prior, S_prior = innovation_gate.prior_innovations(x_pred, P_pred, z, b, A, rs, rc)
    prior = innovation_gate.prior_failures(
        y_prior, S_prior, ca.vertcat(mask_s, mask_c), spread, settings
    )
    gate, record = innovation_gate.gate_rows(reject, spread, settings, prior)
    x_s, P_s, y_s, S_s, use_s = sequential_update_innovations(
        x_pred, P_pred, z, ca.DM.eye(4), rs, mask_s, gate
    )
    x_new, P_new, y_c, S_c, use_c = constraint_update(
        x_s, P_s, b, A, rc, mask_c, lambda i, y, S: gate(4 + i, y, S)
    )
    # No travel row at all (IMU-only): the weak roll-split row observes the warp, beside
    # the roll moment it splits, so only when that row was used (with no data at all the
    # step is a pure prediction).
    no_travel = (1 - mask_s[0]) * (1 - mask_s[1]) * (1 - mask_s[2]) * (1 - mask_s[3])
    mask_split = dt_ok * no_travel * use_c[2]
    r_split = SPLIT_NOISE_RATIO * rc[2:3]
    x_new, P_new = sequential_update(
        x_new, P_new, ca.DM.zeros(1), roll_split_function()(p), r_split, mask_split
    )
    P_new, limited_new = limits.floor_covariance(P_new, settings.covariance_floor)
    # An update that would take a load out of +-load_limit m g (or to a non-finite value)
    # is not taken: the sample is the prediction, so no hostile sample poisons the state.
    total = limits.total_range(m, b[0], mask_c[0], weight)
    bounded = limits.within_load_limit(x_new, x_pred, total, weight, settings)
    x_new = ca.if_else(bounded, x_new, x_pred)
    P_new = ca.if_else(bounded, P_new, P_pred)
    use_s, use_c = use_s * bounded, use_c * bounded

    # The payload filter on the equilibrium at the pseudo-measured loads (every wheel's
    # suspension row and the equilibrium row available).
    all_travel = mask_s[0] * mask_s[1] * mask_s[2] * mask_s[3]
    loaded = payload.update(
        theta, P_theta, z, u_term, gates_term, p_file, all_travel * mask_c * bounded,
        dt_nominal, payload_tuning, residual_theta,
    )  # fmt: skip
    mass_properties, mass_properties_std = payload.reported(
        loaded.theta, loaded.P, p_file, payload_tuning
    )

    # The reported sigma: P and the model's mismatch terms (the gain does not see them).
    features, sigma_means = reported_std.sigma_features(
        P_new, u, z, A, b, mask_s, mask_c, y_s, m, dt_used
    )
    std = reported_std.reported_std(features, tuning[SIGMA_TUNING])
    residual = b - ca.mtimes(A, x_new)
    used = ca.vertcat(use_s, use_c, (1 - dropped) * dt_ok)
    available = ca.vertcat(mask_s, mask_c)
    innovation = ca.vertcat(y_s, y_c) * available
    innovation_variance = ca.vertcat(S_s, S_c) * available
    m_next = monitor_state.MONITOR.pack(
        {
            **watch.m_next,
            "reject": innovation_gate.reject_times(reject, record, available, dt_used),
            "spread": innovation_gate.next_spread(spread, record, available, dt_used, settings),
            **monitor_state.HOLD.unpack(hold_state),
            "settle": settle_next,
            "total": total,
            **monitor_state.SIGMA_MEANS.unpack(sigma_means),
            "payload": loaded.theta,
            "payload_covariance": ca.vec(loaded.P),
            "started": ca.logic_or(started, dt_ok),
            "travel_seen": watch.seen,
        }
    )
    status = _status(
        record, available, valid_raw, in_range, watch.fault,
        ca.logic_or(limited_pred, limited_new), watch.jump, held, 1 - bounded,
    )  # fmt: skip
    inputs = [x, P, m, u_raw, valid_raw, dt, p_file, tuning]
    outputs = [
        x_new, P_new, m_next, std, residual, used, z, innovation, innovation_variance,
        status, watch.statistic, watch.fault, mass_properties, mass_properties_std,
    ]  # fmt: skip
    return inputs, outputs


def _status(record, available, valid_raw, in_range, fault, limited, jump, held, unbounded):
    """Indicators of the guard flags (:data:`GUARD_FLAGS` order)."""

    def any_of(values):
        result = 0
        for value in values:
            result = ca.logic_or(result, value)
        return result

    gated = [available[i] * (1 - ca.logic_or(*record[i][:2])) for i in range(7)]
    released = [available[i] * (1 - record[i][0]) * record[i][1] for i in range(7)]
    implausible = [valid_raw[i] * (1 - in_range[i]) for i in range(len(INPUTS))]
    return ca.vertcat(
        any_of(gated),
        any_of(released),
        any_of([implausible[k] for k in _TRAVEL_INDEX + _RATE_INDEX]),
        any_of([implausible[k] for k in _ACC_INDEX + _HUB_INDEX]),
        implausible[INPUTS.index("vx")],
        any_of([fault[i] for i in range(4)]),
        any_of([fault[i] for i in range(4, 7)]),
        limited,
        any_of([jump[i] for i in range(4)]),
        any_of([implausible[k] for k in _BODY_RATE_INDEX]),
        any_of([held[k] for k in range(len(INPUTS))]),
        unbounded,
    )


def step_function(
    suspension: ca.Function | None = None,
    equilibrium: ca.Function | None = None,
    name: str = STEP_NAME,
    *,
    constraint_update=sequential_update_innovations,
    measurement_noise: ca.Function | None = None,
) -> ca.Function:
    """The filter step as a CasADi Function (model Functions default to ``wheelload.models``)."""
    inputs, outputs = step_expressions(
        suspension or suspension_function(),
        equilibrium or equilibrium_function(),
        constraint_update=constraint_update,
        measurement_noise=measurement_noise,
    )
    # The suspension and equilibrium share the body motion and attitude: one copy.
    outputs = ca.cse(outputs)
    return ca.Function(name, inputs, outputs, STEP_INPUT_NAMES, STEP_OUTPUT_NAMES)


def without_monitor(step: ca.Function) -> ca.Function:
    """``step`` for callers that carry only x and P: the monitor starts empty every call,
    as a started filter's (x and P are the prior, not the diffuse first sample's).

    ``(x, P, u, u_valid, dt, p, tuning) -> (x_next, P_next, std, residual,
    used, z, innovation, innovation_variance)``.
    """
    inputs = step.sx_in()
    m = ca.DM.zeros(step.sparsity_in(2))
    m[monitor_state.STARTED] = 1
    named = dict(zip(STEP_OUTPUT_NAMES, step.call([*inputs[:2], m, *inputs[3:]])))
    kept = [
        name
        for name in STEP_OUTPUT_NAMES
        if name
        not in (
            "m_next",
            "status",
            "fault_statistic",
            "fault",
            "mass_properties",
            "mass_properties_std",
        )  # fmt: skip
    ]
    names_in = [name for name in STEP_INPUT_NAMES if name != "m"]
    return ca.Function(
        f"{step.name()}_xp",
        [*inputs[:2], *inputs[3:]],
        [named[name] for name in kept],
        names_in,
        kept,
    )
