r"""The tyre-force observers' step as one CasADi Function: the Python methods and the C.

:func:`tyre_core_function` is one sample of the observers of
:mod:`~wheelload.estimators.family.tyres.forces` (the PI spin observers of
:math:`F_x`, eq. 4-9 in their implementable form, and the adaptive lateral filter of
:math:`F_y`, eq. 10-16 with §IV's covariance switching), the vehicle's numbers and the
settings folded in. :class:`~wheelload.estimators.family.tyres.forces.TyreForces` steps it
and loops it over a log in compiled C; ``wheelload codegen --tyre-forces`` emits the same
Function as C (:mod:`~wheelload.estimators.codegen.tyre`), so both give one set of numbers.

Missing inputs come as values replaced by 0 and a validity flag per value (the KF's
convention): a missing spin or torque holds the last :math:`F_x` with ``missing_std``; a
missing force sum or yaw rate skips its row of the lateral update exactly
(:func:`~wheelload.estimators.kernels.kalman.update`'s mask); a missing steer angle is 0.

The observers' discretisation depends on the interval alone and enters as a per-sample
input (:func:`observer_inputs`: :math:`\Phi, \Gamma_1, \Gamma_2` and the spin-noise gain
per wheel), so the Function itself needs no matrix exponential.
"""

from __future__ import annotations

import enum

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.kalman import update
from wheelload.models.family.tyre_forces import (
    body_force_rows,
    load_shares,
    observer_gains,
    rolling_resistance_force,
    slip_ratios,
    tyre_split,
    wheel_centre_speeds,
    wheel_lateral_forces,
)
from wheelload.models.vehicle.wheel_geometry import rolling_radius


class LateralSplit(enum.Enum):
    """How an axle's lateral force splits left/right before the filter's :math:`e`."""

    LOAD = "load"  # F_z share: the paper's simple alternative (§III-B)
    TYRE = "tyre"  # the tyres' load sensitivity, by utilisation (models: tyre_split)


class CoreLayout:
    """Where each part of the observers' state lies in the flat ``core`` vector."""

    observer: slice = slice(0, 16)  # per wheel: omega_hat, a_hat, last torque, last spin
    x: slice = slice(16, 22)  # lateral filter: F_yf, F_yr, e, r, torque gain g, S_x bias
    P: slice = slice(22, 58)  # its covariance, 6 x 6 column-major
    last_slip: slice = slice(58, 62)  # slip ratios of the last sample with every spin, speed
    slip_rate: slice = slice(62, 66)  # their rates, low-passed over slip_time
    last_fx: slice = slice(66, 70)  # the last F_x (held through a missing spin or torque)
    observer_started: int = 70  # 1 once a sample had every spin and torque
    lateral_started: int = 71  # 1 after the first sample
    slip_seen: int = 72  # 1 once last_slip holds a sample
    fast_observer: slice = slice(73, 81)  # per wheel: omega_hat, a_hat of the fast observer
    slip_hold: int = 81  # s left on the fast observer after the last high-slip sample
    size: int = 82


CORE = CoreLayout()
#: The lateral filter's state: axle forces, front difference, yaw rate, torque gain and
#: the bias of S_x (the accelerometer's a_x bias times m, the drag's error).
LATERAL_STATES = ("F_yf", "F_yr", "e", "r", "g", "b_x")
#: Per-sample inputs of the wheels: spins (4) [rad/s], torques (4) [N m], steer [rad].
WHEEL_INPUTS = (
    "omega_fl", "omega_fr", "omega_rl", "omega_rr",
    "torque_fl", "torque_fr", "torque_rl", "torque_rr", "steer",
)  # fmt: skip
#: Entries per wheel of :func:`observer_inputs`: Phi (2 x 2), Gamma1, Gamma2 row-major, gain.
OBSERVER_ENTRIES = 13
#: The observers per wheel: the nominal one, then the fast one of high slip.
OBSERVER_BANKS = 2
CORE_INPUTS = ("core", "wheels", "wheels_valid", "sums", "sums_valid", "rate", "rate_valid",
               "speed", "speed_valid", "loads", "mass_properties", "dt", "observer")  # fmt: skip
CORE_OUTPUTS = ("core_next", "fx", "fx_std", "fy", "fy_std", "high_slip")


def observer_inputs(discrete: list[tuple]) -> np.ndarray:
    """The ``observer`` input (13 per entry: the nominal observers' four, then the fast
    ones' four) from each wheel's
    :func:`~wheelload.estimators.family.tyres.forces.discrete_observer` result."""
    rows = [np.concatenate([np.ravel(phi), np.ravel(g1), np.ravel(g2), [gain]])
            for phi, g1, g2, _, _, gain in discrete]  # fmt: skip
    return np.concatenate(rows)


def _all(flags) -> ca.SX:
    """1 where every flag is 1 (flags are exactly 0 or 1)."""
    result = flags[0]
    for k in range(1, flags.shape[0]):
        result = result * flags[k]
    return result


def _select(condition, when_true, when_false):
    return ca.if_else(condition, when_true, when_false, True)


def tyre_core_function(
    constants, settings, high_slip_scales: tuple[float, float], parameters: ca.SX | None = None
) -> ca.Function:
    """``tyre_core(core, wheels, wheels_valid, sums, sums_valid, rate, rate_valid, speed,
    speed_valid, loads, mass_properties, dt, observer) -> (core_next, fx, fx_std, fy, fy_std,
    high_slip)`` (module docstring).

    ``constants``: :class:`~wheelload.estimators.family.tyres.forces.Constants`;
    ``settings``: :class:`~wheelload.estimators.family.tyres.forces.TyreSettings`;
    ``high_slip_scales``: the factors on Q and R in high slip; ``mass_properties``: the
    KF's online ``[m', δx, y_c', h']`` (the file's where the payload is not estimated).
    ``parameters``: the symbols some of the ``constants`` are made of (the generated C's
    run-time tyre parameters), then the Function's last input ``parameters``.
    """
    k, s = constants, settings
    core = ca.SX.sym("core", CORE.size)
    wheels = ca.SX.sym("wheels", len(WHEEL_INPUTS))
    wheels_valid = ca.SX.sym("wheels_valid", len(WHEEL_INPUTS))
    sums = ca.SX.sym("sums", 2)
    sums_valid = ca.SX.sym("sums_valid", 2)
    rate, rate_valid = ca.SX.sym("rate"), ca.SX.sym("rate_valid")
    speed, speed_valid = ca.SX.sym("speed"), ca.SX.sym("speed_valid")
    loads = ca.SX.sym("loads", 4)
    mass_properties = ca.SX.sym("mass_properties", 4)
    dt = ca.SX.sym("dt")
    observer = ca.SX.sym("observer", OBSERVER_BANKS * 4 * OBSERVER_ENTRIES)
    spin, torque, steer = wheels[0:4], wheels[4:8], wheels[8]
    spins_valid = _all(wheels_valid[0:4])
    inputs_valid = spins_valid * _all(wheels_valid[4:8])
    started = core[CORE.observer_started]
    n = len(LATERAL_STATES)
    steer = steer * wheels_valid[8]

    # §IV's high slip: a wheel's slip ratio (on its effective rolling radius under the KF's
    # load) changing faster than slip_ratio_rate, low-passed over slip_time (a kerb's spin
    # oscillation averages out).
    deflection = ca.fmax(loads, 0.0) / ca.DM(k.vertical_stiffness)
    speeds = wheel_centre_speeds(speed, rate * rate_valid, steer, k.positions)
    slip = slip_ratios(spin, rolling_radius(ca.DM(k.free_radius), deflection), speeds,
                       s.slip_speed)  # fmt: skip
    slip_valid = spins_valid * speed_valid
    seen = core[CORE.slip_seen] * slip_valid * (dt > 0)
    raw_rate = (slip - core[CORE.last_slip]) / ca.fmax(dt, 1e-9)
    blend = dt / (s.slip_time + dt)
    slip_rate = _select(seen, core[CORE.slip_rate] + blend * (raw_rate - core[CORE.slip_rate]),
                        core[CORE.slip_rate])  # fmt: skip
    high_slip = seen * (ca.mmax(ca.fabs(slip_rate)) >= s.slip_ratio_rate)

    # F_x: eq. 4-5's spin observers, the nominal one and the fast one that F_x rides in
    # high slip and slip_hold after it (a cycling ABS moves the force faster than the
    # nominal one follows); their force split into the torque's feed-through T / R (scaled
    # by the lateral filter's torque gain g) and the rest.
    hold = _select(high_slip, s.slip_hold, ca.fmax(core[CORE.slip_hold] - dt, 0.0))
    fast = hold >= 0.5 * dt
    frequencies = (s.observer_frequency, s.slip_observer_frequency)
    observers, fast_observers, fx_rest, fx_torque, fx_noise = [], [], [], [], []
    for i in range(4):
        state = core[CORE.observer][4 * i : 4 * i + 4]
        fast_state = core[CORE.fast_observer][2 * i : 2 * i + 2]
        previous = state[2:4]
        u = ca.vertcat(torque[i], spin[i])
        first = ca.vertcat(spin[i], 0.0)  # start rolling steadily: F = T / R
        z, rest, gain = [], [], []
        for bank, z_last in enumerate((state[0:2], fast_state)):
            k1, _ = observer_gains(inertia=k.inertia[i], radius=k.radius[i],
                                   frequency=frequencies[bank],
                                   damping=s.observer_damping)  # fmt: skip
            start = OBSERVER_ENTRIES * (4 * bank + i)
            entries = observer[start : start + OBSERVER_ENTRIES]
            phi, g1, g2 = (ca.reshape(entries[4 * j : 4 * j + 4], 2, 2).T for j in range(3))
            z_next = _select(started, ca.mtimes(phi, z_last) + ca.mtimes(g1, previous)
                             + ca.mtimes(g2, u - previous), first)  # fmt: skip
            z.append(z_next)
            # C z + D u of observer_matrices, the torque's part apart.
            rest.append(k1 * z_next[0] - k.inertia[i] / k.radius[i] * z_next[1] - k1 * spin[i])
            gain.append(entries[12])
        observers.append(_select(inputs_valid, ca.vertcat(z[0], u), state))
        fast_observers.append(_select(inputs_valid, z[1], fast_state))
        rolling = rolling_resistance_force(loads[i], spin[i], k.rolling)
        fx_rest.append(_select(fast, rest[1], rest[0]) - rolling)
        fx_torque.append(torque[i] / k.radius[i])
        fx_noise.append((_select(fast, gain[1], gain[0]) * s.spin_noise) ** 2
                        + (s.rolling_resistance_std * rolling) ** 2)  # fmt: skip
    fx_rest, fx_torque = ca.vertcat(*fx_rest), ca.vertcat(*fx_torque)

    # The lateral filter (eq. 10-16) with the torque gain, initialised on the first sample.
    lateral = core[CORE.lateral_started]
    x = _select(lateral, core[CORE.x], ca.vertcat(0.0, 0.0, 0.0, rate * rate_valid, 1.0, 0.0))
    P0 = ca.diag(ca.DM([s.initial_force_std**2] * 2
                       + [s.split_std**2, s.gyro_noise**2, s.torque_gain_std**2,
                          s.force_bias_std**2]))  # fmt: skip
    P = _select(lateral, ca.reshape(core[CORE.P], n, n), P0)
    switched = high_slip * float(s.switch_covariances)
    q_scale = _select(switched, high_slip_scales[0], 1.0)
    r_scale = _select(switched, high_slip_scales[1], 1.0)

    # The loaded car: mass, CG shift (the KF's payload).
    mass, shift = mass_properties[0], ca.vertcat(mass_properties[1], mass_properties[2] - k.cg_y)
    if s.split is LateralSplit.LOAD:
        shares = load_shares(loads)
    else:
        shares = tyre_split(loads, x[0:2], nominal_loads=k.nominal_loads, friction=k.friction,
                            load_sensitivity=k.load_sensitivity,
                            cornering_load=k.cornering_load)  # fmt: skip
    rows = dict(
        lf=k.lf,
        lr=k.lr,
        track_front=k.track_front,
        track_rear=k.track_rear,
        share_front=shares[1] - shares[0],
        inertia_z=k.yaw_inertia,
        cg_shift=shift,
    )
    h, offset = body_force_rows(steer, fx_rest, **rows)
    _, by_gain = body_force_rows(steer, fx_torque, **rows)  # the rows' g column
    h = ca.horzcat(h, by_gain)
    # Predict: forces and gain random walks, r integrated from eq. 3's yaw acceleration.
    F = ca.SX.eye(n)
    F[3, [0, 1, 2, 4]] = dt * h[2, [0, 1, 2, 3]]
    x = ca.mtimes(F, x) + ca.vertcat(0.0, 0.0, 0.0, dt * offset[2], 0.0, 0.0)
    Q = q_scale * dt * ca.diag(ca.DM([s.force_rate**2, s.force_rate**2, s.split_rate**2,
                                      s.yaw_rate_noise**2, s.torque_gain_rate**2,
                                      s.force_bias_rate**2]))  # fmt: skip
    P = ca.mtimes([F, P, F.T]) + Q
    # Update: S_x, S_y at the IMU (lever arm: m x_imu r_dot), and the gyro's r.
    lever = mass * (k.imu_x - shift[0])
    H = ca.vertcat(
        ca.horzcat(h[0, 0:3], 0.0, h[0, 3], 1.0),
        ca.horzcat(h[1, 0:3] + lever * h[2, 0:3], 0.0, h[1, 3] + lever * h[2, 3], 0.0),
        ca.DM([[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]]),
    )  # fmt: skip
    z = ca.vertcat(sums[0] - offset[0], sums[1] - offset[1] - lever * offset[2], rate)
    R = r_scale * ca.diag(ca.DM([s.force_noise**2, s.force_noise**2, s.gyro_noise**2]))
    x, P = update(x, P, z, H, R, ca.vertcat(sums_valid, rate_valid))
    fy, G = wheel_lateral_forces(x[0:3], shares)  # the shares of the predicted forces
    fy_std = ca.sqrt(ca.fmax(ca.diag(ca.mtimes([G, P[0:3, 0:3], G.T])), 0.0))

    # F_x with the updated gain, held where a spin or torque is missing.
    force = fx_rest + x[4] * fx_torque
    variance = ca.vertcat(*fx_noise) + (s.force_share_std * force) ** 2 + fx_torque**2 * P[4, 4]
    last_fx = core[CORE.last_fx]
    fx = _select(inputs_valid, force, last_fx)
    fx_std = _select(inputs_valid, ca.sqrt(variance), s.missing_std)

    core_next = ca.vertcat(
        *observers, x, ca.reshape(P, n * n, 1),
        _select(slip_valid, slip, core[CORE.last_slip]), slip_rate, fx,
        ca.fmax(started, inputs_valid), 1.0, ca.fmax(core[CORE.slip_seen], slip_valid),
        *fast_observers, hold,
    )  # fmt: skip
    inputs = [core, wheels, wheels_valid, sums, sums_valid, rate, rate_valid, speed,
              speed_valid, loads, mass_properties, dt, observer]  # fmt: skip
    names = list(CORE_INPUTS)
    if parameters is not None:
        inputs, names = [*inputs, parameters], [*names, "parameters"]
    return ca.Function(
        "tyre_core",
        inputs,
        [core_next, fx, fx_std, fy, fy_std, high_slip],
        names,
        list(CORE_OUTPUTS),
    )
