r"""The stages of the two-stage KF's step (Siegloff & Choi §III, method A), each a builder
``build(**values) -> {name: value}`` over SX that :mod:`wheelload.estimators.kf.step` turns
into a named Function ``wheelload_kf_<stage>`` and composes.

In order (:func:`step_stages`): the interval; the payload's loaded parameters; plausibility and
holds of the inputs; the model rows (suspension pseudo-measurement eq. 13, equilibrium eq.
14-17) and their masks; the fault monitor; the noise (eq. 19-25); the random-walk predict
(eq. 12, 19); the innovation gate; the suspension update (eq. 20-22); the equilibrium update as
a soft constraint (eq. 23-25); the roll split; the load limits; the payload update; the
reported sigma; the next carried state; the outputs and status bits.
"""

from __future__ import annotations

import functools

import casadi as ca

from wheelload.estimators.guards import (
    fault_monitor,
    innovation_gate,
    limits,
    plausibility,
)
from wheelload.estimators.guards import settings as guard
from wheelload.estimators.guards.monitor_state import HOLD, MONITOR, SIGMA_MEANS, WATCH
from wheelload.estimators.kernels.kalman import (
    predict,
    sequential_update,
    sequential_update_innovations,
    upper,
)
from wheelload.estimators.kf import payload, reported_std
from wheelload.estimators.kf.model_rows import (
    ACC_INDEX,
    RATE_INDEX,
    TRAVEL_INDEX,
    channel_drop,
    model_equations,
    row_masks,
)
from wheelload.estimators.kf.tuning import GUARD_TUNING, PAYLOAD_SLICE, SIGMA_TUNING, TUNING
from wheelload.models import (
    GRAVITY,
    INPUTS,
    ModelParameters,
    gates_function,
)
from wheelload.models.input_validity import interval_is_valid, sanitise
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    input_index,
)
from wheelload.models.loaded_vehicle import loaded_parameters_function
from wheelload.models.measurement_noise import DENSITIES as NOISE_DENSITY_ORDER
from wheelload.models.roll_split import SPLIT_NOISE_RATIO, roll_split_function
from wheelload.models.terms import parity_model

_P_INDEX = {name: k for k, name in enumerate(ModelParameters.names())}


_HUB_INDEX = input_index(HUB_ACCELERATION)


_BODYRATE_INDEX = input_index(BODY_RATES + BODY_RATE_DERIVATIVES)


def step_stages(suspension, equilibrium, *, constraint_update, measurement_noise) -> tuple:
    """The step's stages in order, each ``build(**values) -> {name: value}`` over SX."""
    models = {"suspension": suspension, "equilibrium": equilibrium}
    return (
        _interval,
        _payload,
        _plausibility,
        functools.partial(_model, **models),
        functools.partial(_monitor, **models),
        functools.partial(_masks, **models),
        functools.partial(_noise, measurement_noise=measurement_noise),
        _predict,
        _gate,
        _suspension_update,
        functools.partial(_equilibrium_update, constraint_update=constraint_update),
        _roll_split,
        _limits,
        functools.partial(_payload_update, equilibrium=equilibrium),
        _sigma,
        _monitor_next,
        _outputs,
    )


def _interval(dt, tuning):
    """A non-positive or non-finite interval skips the whole step: the state is held; so
    does one below the nominal interval (tuning ``sample_interval``, which sets the
    measurement noise) over the guard setting ``interval_band`` (the log is faster than the
    nominal interval says: ``short``); one above it times the band is taken (``long``)."""
    nominal = TUNING.value(tuning, "sample_interval")
    band = TUNING.value(tuning, "interval_band")
    valid = interval_is_valid(dt)
    short = ca.logic_and(valid, dt * band < nominal)
    long = ca.logic_and(valid, dt > nominal * band)
    dt_ok = ca.logic_and(valid, 1 - short)
    dt_safe = ca.if_else(dt_ok, dt, 1.0)
    return {"dt_ok": dt_ok, "dt_used": dt_safe * dt_ok, "short": short, "long": long}


def _payload(m, u_raw, valid_raw, dt_used, p_file, tuning):
    """The payload the file does not know (:mod:`.payload`), predicted to this sample, and
    the loaded vehicle's parameters every row below sees (the suspension's offsets stay the
    reference state's)."""
    payload_tuning = tuning[PAYLOAD_SLICE]
    theta, P_theta = payload.predict(
        MONITOR.value(m, "payload"),
        ca.reshape(MONITOR.value(m, "payload_covariance"), 4, 4),
        MONITOR.value(m, "started"),
        sanitise(u_raw, valid_raw),
        valid_raw,
        dt_used,
        payload_tuning,
    )
    p = loaded_parameters_function()(p_file, payload.applied(theta, payload_tuning))
    return {"theta": theta, "P_theta": P_theta, "p": p}


def _plausibility(u_raw, valid_raw, m, dt_used, p, tuning):
    """Missing or implausible inputs are replaced by zero and skip the updates they feed (a
    body rate that jumps, or a derivative after a gated rate, counts as implausible); the
    model terms take each missing or gated input's last valid value for ``hold_time``."""
    settings = guard.unpack(tuning[GUARD_TUNING])
    u_finite = sanitise(u_raw, valid_raw)
    in_range = plausibility.plausible_for(u_finite, p, settings)
    consistent, settle_next = plausibility.rate_consistency(
        u_finite, valid_raw, in_range, m, dt_used, settings
    )
    in_range = in_range * consistent
    valid_plausible = valid_raw * in_range
    u = sanitise(u_raw, valid_plausible)
    u_term, valid_term, held, hold_state = plausibility.hold_inputs(
        u, valid_plausible, m, dt_used, settings
    )
    return {
        "in_range": in_range, "settle_next": settle_next, "valid_plausible": valid_plausible,
        "u": u, "u_term": u_term, "valid_term": valid_term, "held": held,
        "hold_state": hold_state,
    }  # fmt: skip


def _model(u_term, valid_term, valid_plausible, p, *, suspension, equilibrium):
    """The pseudo-measurement and the equilibrium on the terms' inputs; ``dropped`` (the
    flags) marks a term without a live input, held or dropped."""
    z, A, b, _ = model_equations(suspension, equilibrium, u_term, valid_term, p)
    dropped = gates_function()(valid_plausible, p)[1]
    gates_term = gates_function()(valid_term, p)[0]
    return {"z": z, "A": A, "b": b, "dropped": dropped, "gates_term": gates_term}


def _monitor(
    m, u, valid_plausible, u_term, valid_term, p, theta, P_theta, z, gates_term, p_file,
    dt_used, tuning, *, suspension, equilibrium,
):  # fmt: skip
    """Fault monitor (:mod:`.fault_monitor`): its parity test uses every model term the
    inputs allow (held inputs included), weighs the constant densities (the paper's R_c),
    and allows for what the payload not yet learnt may leave in the residual."""
    settings = guard.unpack(tuning[GUARD_TUNING])
    parity = parity_model(suspension, equilibrium, u_term, valid_term, p)
    rc_density = TUNING.value(tuning, "constraint_noise_density")
    residual_theta = payload.residual_function(equilibrium)
    unexplained = payload.unexplained(
        theta, P_theta, z, u_term, gates_term, p_file, tuning[PAYLOAD_SLICE], residual_theta
    )
    watch = fault_monitor.monitor(
        m, u, valid_plausible, *parity, dt_used, rc_density, settings, unexplained
    )
    return {
        "monitor_next": WATCH.pack(watch.m_next), "channel_ok": watch.channel_ok,
        "fault_statistic": watch.statistic, "fault": watch.fault, "jump": watch.jump,
        "seen": watch.seen,
    }  # fmt: skip


def _masks(u_raw, valid_plausible, channel_ok, p, dt_ok, *, suspension, equilibrium):
    """The updates the channels left after the guards feed: an isolated channel is dropped
    like a missing one (the model terms keep their inputs, as for the monitor)."""
    u = sanitise(u_raw, valid_plausible)
    valid = valid_plausible * channel_drop(channel_ok)
    mask_s, mask_c = row_masks(suspension, equilibrium, u, u_raw, valid, p)
    return {"mask_s": mask_s * dt_ok, "mask_c": mask_c * dt_ok}


def _noise(u, valid_plausible, p, dt_used, tuning, *, measurement_noise):
    """Q, R_s and R_c (models/measurement_noise.py) from the nominal interval: a gap grows P,
    never shrinks R; the covariance ceiling and the weight of the loaded vehicle."""
    ceiling = limits.variance_ceiling(p[_P_INDEX["mass"]])
    q = TUNING.value(tuning, "process_noise_density")
    Q = ca.fmin(q * dt_used, ceiling) * ca.DM.eye(4)
    densities = TUNING.values(tuning, NOISE_DENSITY_ORDER)
    rs, rc = measurement_noise(
        u, valid_plausible, densities, TUNING.value(tuning, "sample_interval")
    )
    weight = p[_P_INDEX["mass"]] * GRAVITY
    return {"Q": Q, "rs": rs, "rc": rc, "ceiling": ceiling, "weight": weight}


def _predict(x, P, Q, ceiling, m, dt_ok, tuning):
    """The random-walk prediction (eq. 19), its covariance within the limits; the first
    sample sees no prior information, so its rows set the loads (an invalid interval holds
    the state, so the start waits for the first valid one)."""
    settings = guard.unpack(tuning[GUARD_TUNING])
    x_pred, P_pred = predict(x, upper(P), Q)
    P_pred, limited_pred = limits.limit_covariance(P_pred, settings.covariance_floor, ceiling)
    started = MONITOR.value(m, "started")
    P_pred = ca.if_else(ca.logic_or(started, 1 - dt_ok), P_pred, ceiling * ca.DM.eye(4))
    return {"x_pred": x_pred, "P_pred": P_pred, "limited_pred": limited_pred}


def _gate(x_pred, P_pred, z, b, A, rs, rc, mask_s, mask_c, m, tuning):
    """The rows that fail the innovation gate against the prediction
    (:func:`.innovation_gate.prior_failures`): a failing row of the other group releases."""
    settings = guard.unpack(tuning[GUARD_TUNING])
    y_prior, S_prior = innovation_gate.prior_innovations(x_pred, P_pred, z, b, A, rs, rc)
    suspension, constraint, count = innovation_gate.prior_failures(
        y_prior, S_prior, ca.vertcat(mask_s, mask_c), MONITOR.value(m, "spread"), settings
    )
    return {"prior_suspension": suspension, "prior_constraint": constraint, "prior_count": count}


def _suspension_update(
    x_pred, P_pred, z, rs, mask_s, m, tuning, prior_suspension, prior_constraint, prior_count
):
    """The suspension pseudo-measurement update, row by row through the gate (eq. 20-22)."""
    gate, record = _gate_rows(m, tuning, prior_suspension, prior_constraint, prior_count)
    x_s, P_s, y_s, S_s, use_s = sequential_update_innovations(
        x_pred, P_pred, z, ca.DM.eye(4), rs, mask_s, gate
    )
    return {"x_s": x_s, "P_s": P_s, "y_s": y_s, "S_s": S_s, "use_s": use_s,
            **_decisions(record, range(4), "s")}  # fmt: skip


def _equilibrium_update(
    x_s, P_s, b, A, rc, mask_c, m, tuning, prior_suspension, prior_constraint, prior_count,
    passes_s, *, constraint_update,
):  # fmt: skip
    """The equilibrium as a soft constraint (eq. 23-25) through the gate; a failing
    suspension row of this sample releases the constraint rows."""
    gate, record = _gate_rows(m, tuning, prior_suspension, prior_constraint, prior_count, passes_s)
    x_c, P_c, y_c, S_c, use_c = constraint_update(
        x_s, P_s, b, A, rc, mask_c, lambda i, y, S: gate(4 + i, y, S)
    )
    return {"x_c": x_c, "P_c": P_c, "y_c": y_c, "S_c": S_c, "use_c": use_c,
            **_decisions(record, range(4, 7), "c")}  # fmt: skip


def _gate_rows(m, tuning, prior_suspension, prior_constraint, prior_count, passes_s=None):
    """The innovation gate on the monitor's rejection times and spreads."""
    return innovation_gate.gate_rows(
        MONITOR.value(m, "reject"),
        MONITOR.value(m, "spread"),
        guard.unpack(tuning[GUARD_TUNING]),
        (prior_suspension, prior_constraint, prior_count),
        passes_s,
    )


def _decisions(record, rows, group: str) -> dict:
    """The gate's record of ``rows``: passes, released, and the y and S it saw."""
    return {
        f"{name}_{group}": ca.vertcat(*[record[i][k] for i in rows])
        for k, name in enumerate(("passes", "released", "gate_y", "gate_S"))
    }


def _roll_split(x_c, P_c, mask_s, use_c, rc, p, dt_ok):
    """No travel row at all (IMU-only): the weak roll-split row observes the warp, beside
    the roll moment it splits, so only when that row was used (with no data at all the step
    is a pure prediction)."""
    no_travel = (1 - mask_s[0]) * (1 - mask_s[1]) * (1 - mask_s[2]) * (1 - mask_s[3])
    mask_split = dt_ok * no_travel * use_c[2]
    r_split = SPLIT_NOISE_RATIO * rc[2:3]
    x_split, P_split = sequential_update(
        x_c, P_c, ca.DM.zeros(1), roll_split_function()(p), r_split, mask_split
    )
    return {"x_split": x_split, "P_split": P_split}


def _limits(x_split, P_split, x_pred, P_pred, b, mask_c, use_s, use_c, m, weight, tuning):
    """The covariance floor; an update that would take a load out of +-load_limit m g (or
    to a non-finite value) is not taken: the sample is the prediction, so no hostile sample
    poisons the state."""
    settings = guard.unpack(tuning[GUARD_TUNING])
    P_floor, limited_new = limits.floor_covariance(P_split, settings.covariance_floor)
    total = limits.total_range(m, b[0], mask_c[0], weight)
    bounded = limits.within_load_limit(x_split, x_pred, total, weight, settings)
    return {
        "x_next": ca.if_else(bounded, x_split, x_pred),
        "P_next": ca.if_else(bounded, P_floor, P_pred),
        "used_s": use_s * bounded, "used_c": use_c * bounded, "bounded": bounded,
        "total": total, "limited_new": limited_new,
    }  # fmt: skip


def _payload_update(
    theta, P_theta, z, u_term, gates_term, p_file, mask_s, mask_c, bounded, tuning, *,
    equilibrium,
):  # fmt: skip
    """The payload filter on the equilibrium at the pseudo-measured loads (every wheel's
    suspension row and the equilibrium row available), and the mass properties reported."""
    payload_tuning = tuning[PAYLOAD_SLICE]
    all_travel = mask_s[0] * mask_s[1] * mask_s[2] * mask_s[3]
    loaded = payload.update(
        theta, P_theta, z, u_term, gates_term, p_file, all_travel * mask_c * bounded,
        TUNING.value(tuning, "sample_interval"), payload_tuning,
        payload.residual_function(equilibrium),
    )  # fmt: skip
    mass_properties, mass_properties_std = payload.reported(
        loaded.theta, loaded.P, p_file, payload_tuning
    )
    return {
        "theta_next": loaded.theta,
        "P_theta_next": loaded.P,
        "mass_properties": mass_properties,
        "mass_properties_std": mass_properties_std,
    }


def _sigma(P_next, u, valid_plausible, z, A, b, mask_s, mask_c, y_s, m, dt_used, tuning):
    """The reported sigma (:mod:`.reported_std`): P and the model's mismatch terms (the gain
    does not see them)."""
    features, sigma_means = reported_std.sigma_features(
        P_next, u, valid_plausible, z, A, b, mask_s, mask_c, y_s, m, dt_used
    )
    std = reported_std.reported_std(features, tuning[SIGMA_TUNING])
    return {"std": std, "sigma_means": sigma_means}


def _monitor_next(
    m, monitor_next, mask_s, mask_c, passes_s, passes_c, released_s, released_c, gate_y_s,
    gate_y_c, gate_S_s, gate_S_c, hold_state, settle_next, total, sigma_means, theta_next,
    P_theta_next, seen, dt_used, dt_ok, tuning,
):  # fmt: skip
    """The carried state after the sample, field by field (:data:`.monitor_state.MONITOR`)."""
    record = _record(passes_s, passes_c, released_s, released_c, gate_y_s, gate_y_c,
                     gate_S_s, gate_S_c)  # fmt: skip
    available = ca.vertcat(mask_s, mask_c)
    reject, spread = MONITOR.value(m, "reject"), MONITOR.value(m, "spread")
    settings = guard.unpack(tuning[GUARD_TUNING])
    m_next = MONITOR.pack(
        {
            **WATCH.unpack(monitor_next),
            "reject": innovation_gate.reject_times(reject, record, available, dt_used),
            "spread": innovation_gate.next_spread(spread, record, available, dt_used, settings),
            **HOLD.unpack(hold_state),
            "settle": settle_next,
            "total": total,
            **SIGMA_MEANS.unpack(sigma_means),
            "payload": theta_next,
            "payload_covariance": ca.vec(P_theta_next),
            "started": ca.logic_or(MONITOR.value(m, "started"), dt_ok),
            "travel_seen": seen,
        }
    )
    return {"m_next": m_next}


def _outputs(
    x_next, A, b, mask_s, mask_c, used_s, used_c, dropped, dt_ok, y_s, y_c, S_s, S_c,
    passes_s, passes_c, released_s, released_c, valid_raw, in_range, fault, limited_pred,
    limited_new, jump, held, bounded, short, long,
):  # fmt: skip
    """The step's reported outputs: residual, used rows, innovations and the guard flags
    (the interval's two last)."""
    available = ca.vertcat(mask_s, mask_c)
    record = _record(passes_s, passes_c, released_s, released_c)
    status = _status(
        record, available, valid_raw, in_range, fault,
        ca.logic_or(limited_pred, limited_new), jump, held, 1 - bounded,
    )  # fmt: skip
    status = ca.vertcat(status, short, long)
    return {
        "residual": b - ca.mtimes(A, x_next),
        "used": ca.vertcat(used_s, used_c, (1 - dropped) * dt_ok),
        "innovation": ca.vertcat(y_s, y_c) * available,
        "innovation_variance": ca.vertcat(S_s, S_c) * available,
        "status": status,
    }


def _record(passes_s, passes_c, released_s, released_c, *seen) -> dict:
    """The gate's record by row (update order): passes, released[, y, S]."""
    columns = [ca.vertcat(passes_s, passes_c), ca.vertcat(released_s, released_c)]
    columns += [ca.vertcat(seen[k], seen[k + 1]) for k in range(0, len(seen), 2)]
    return {i: tuple(column[i] for column in columns) for i in range(7)}


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
        any_of([implausible[k] for k in TRAVEL_INDEX + RATE_INDEX]),
        any_of([implausible[k] for k in ACC_INDEX + _HUB_INDEX]),
        implausible[INPUTS.index("vx")],
        any_of([fault[i] for i in range(4)]),
        any_of([fault[i] for i in range(4, 7)]),
        limited,
        any_of([jump[i] for i in range(4)]),
        any_of([implausible[k] for k in _BODYRATE_INDEX]),
        any_of([held[k] for k in range(len(INPUTS))]),
        unbounded,
    )
