r"""The tyre-force observers' step as one CasADi Function: the Python methods and the C.

:func:`tyre_core_function` is one sample of the observers of
:mod:`~wheelload.estimators.family.tyre_forces` (the PI spin observers of
:math:`F_x`, eq. 4-9 in their implementable form, and the adaptive lateral filter of
:math:`F_y`, eq. 10-16 with §IV's covariance switching), the vehicle's numbers and the
settings folded in. :class:`~wheelload.estimators.family.tyre_forces.TyreForces` steps it
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
    tyre_split,
    wheel_lateral_forces,
)


class LateralSplit(enum.Enum):
    """How an axle's lateral force splits left/right before the filter's :math:`e`."""

    LOAD = "load"  # F_z share: the paper's simple alternative (§III-B)
    TYRE = "tyre"  # the tyres' load sensitivity, by utilisation (models: tyre_split)


class CoreLayout:
    """Where each part of the observers' state lies in the flat ``core`` vector."""

    observer: slice = slice(0, 16)  # per wheel: omega_hat, xi, last torque, last spin
    x: slice = slice(16, 20)  # lateral filter: F_yf, F_yr, e, r
    P: slice = slice(20, 36)  # its covariance, 4 x 4 column-major
    last_spin: slice = slice(36, 40)  # spins of the last sample with all four
    last_fx: slice = slice(40, 44)  # the last F_x (held through a missing spin or torque)
    observer_started: int = 44  # 1 once a sample had every spin and torque
    lateral_started: int = 45  # 1 after the first sample
    spin_seen: int = 46  # 1 once last_spin holds a sample
    size: int = 47


CORE = CoreLayout()
#: Per-sample inputs of the wheels: spins (4) [rad/s], torques (4) [N m], steer [rad].
WHEEL_INPUTS = (
    "omega_fl", "omega_fr", "omega_rl", "omega_rr",
    "torque_fl", "torque_fr", "torque_rl", "torque_rr", "steer",
)  # fmt: skip
#: Entries per wheel of :func:`observer_inputs`: Phi (2 x 2), Gamma1, Gamma2 row-major, gain.
OBSERVER_ENTRIES = 13
CORE_INPUTS = ("core", "wheels", "wheels_valid", "sums", "sums_valid", "rate", "rate_valid",
               "loads", "dt", "observer")  # fmt: skip
CORE_OUTPUTS = ("core_next", "fx", "fx_std", "fy", "fy_std", "high_slip")


def observer_inputs(discrete: list[tuple]) -> np.ndarray:
    """The ``observer`` input (52,) from each wheel's
    :func:`~wheelload.estimators.family.tyre_forces.discrete_observer` result."""
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


def tyre_core_function(constants, settings, high_slip_scales: tuple[float, float]) -> ca.Function:
    """``tyre_core(core, wheels, wheels_valid, sums, sums_valid, rate, rate_valid, loads,
    dt, observer) -> (core_next, fx, fx_std, fy, fy_std, high_slip)`` (module docstring).

    ``constants``: :class:`~wheelload.estimators.family.tyre_forces.Constants`;
    ``settings``: :class:`~wheelload.estimators.family.tyre_forces.TyreSettings`;
    ``high_slip_scales``: the factors on Q and R in high slip.
    """
    k, s = constants, settings
    core = ca.SX.sym("core", CORE.size)
    wheels = ca.SX.sym("wheels", len(WHEEL_INPUTS))
    wheels_valid = ca.SX.sym("wheels_valid", len(WHEEL_INPUTS))
    sums = ca.SX.sym("sums", 2)
    sums_valid = ca.SX.sym("sums_valid", 2)
    rate, rate_valid = ca.SX.sym("rate"), ca.SX.sym("rate_valid")
    loads = ca.SX.sym("loads", 4)
    dt = ca.SX.sym("dt")
    observer = ca.SX.sym("observer", 4 * OBSERVER_ENTRIES)
    spin, torque, steer = wheels[0:4], wheels[4:8], wheels[8]
    spins_valid = _all(wheels_valid[0:4])
    inputs_valid = spins_valid * _all(wheels_valid[4:8])
    started = core[CORE.observer_started]

    # F_x: the spin observers (tyre_forces._fx), held where a spin or torque is missing.
    observers, fx, fx_std = [], [], []
    last_fx = core[CORE.last_fx]
    for i in range(4):
        k1, k2 = observer_gains(inertia=k.inertia[i], radius=k.radius[i],
                                frequency=s.observer_frequency,
                                damping=s.observer_damping)  # fmt: skip
        entries = observer[OBSERVER_ENTRIES * i : OBSERVER_ENTRIES * (i + 1)]
        phi, g1, g2 = (ca.reshape(entries[4 * j : 4 * j + 4], 2, 2).T for j in range(3))
        gain = entries[12]
        state = core[CORE.observer][4 * i : 4 * i + 4]
        z, previous = state[0:2], state[2:4]
        u = ca.vertcat(torque[i], spin[i])
        # Start in equilibrium: F = -k2 xi = T / R, no spin error.
        first = ca.vertcat(spin[i], -(torque[i] / k.radius[i]) / k2)
        z = _select(started, ca.mtimes(phi, z) + ca.mtimes(g1, previous)
                    + ca.mtimes(g2, u - previous), first)  # fmt: skip
        observers.append(_select(inputs_valid, ca.vertcat(z, u), state))
        rolling = rolling_resistance_force(loads[i], spin[i], k.rolling)
        force = k1 * z[0] - k2 * z[1] - k1 * spin[i] - rolling  # C z + D u - rolling
        std = ca.sqrt((gain * s.spin_noise) ** 2 + (s.rolling_resistance_std * rolling) ** 2
                      + (s.force_share_std * force) ** 2)  # fmt: skip
        fx.append(_select(inputs_valid, force, last_fx[i]))
        fx_std.append(_select(inputs_valid, std, s.missing_std))
    fx, fx_std = ca.vertcat(*fx), ca.vertcat(*fx_std)

    # F_y: the lateral filter (tyre_forces._fy), initialised on the first sample.
    lateral = core[CORE.lateral_started]
    x = _select(lateral, core[CORE.x], ca.vertcat(0.0, 0.0, 0.0, rate * rate_valid))
    P0 = ca.diag(ca.DM([s.initial_force_std**2] * 2 + [s.split_std**2, s.gyro_noise**2]))
    P = _select(lateral, ca.reshape(core[CORE.P], 4, 4), P0)
    steer = steer * wheels_valid[8]
    last_spin = core[CORE.last_spin]
    fastest = ca.mmax(ca.fabs(spin - last_spin) - s.slip_threshold * dt)
    high_slip = core[CORE.spin_seen] * spins_valid * (dt > 0) * (fastest >= 0)
    q_scale = _select(high_slip, high_slip_scales[0], 1.0)
    r_scale = _select(high_slip, high_slip_scales[1], 1.0)
    if s.split is LateralSplit.LOAD:
        shares = load_shares(loads)
    else:
        shares = tyre_split(loads, x[0:2], nominal_loads=k.nominal_loads, friction=k.friction,
                            load_sensitivity=k.load_sensitivity,
                            cornering_load=k.cornering_load)  # fmt: skip
    h, offset = body_force_rows(steer, fx, lf=k.lf, lr=k.lr, track_front=k.track_front,
                                track_rear=k.track_rear, share_front=shares[1] - shares[0],
                                inertia_z=k.yaw_inertia)  # fmt: skip
    # Predict: forces random walk, r integrated from eq. 3's yaw acceleration.
    F = ca.SX.eye(4)
    F[3, 0:3] = dt * h[2, :]
    x = ca.mtimes(F, x) + ca.vertcat(0.0, 0.0, 0.0, dt * offset[2])
    Q = q_scale * dt * ca.diag(ca.DM([s.force_rate**2, s.force_rate**2, s.split_rate**2,
                                      s.yaw_rate_noise**2]))  # fmt: skip
    P = ca.mtimes([F, P, F.T]) + Q
    # Update: S_x, S_y at the IMU (lever arm: m x_imu r_dot), and the gyro's r.
    lever = k.mass * k.imu_x
    H = ca.vertcat(
        ca.horzcat(h[0, :], 0.0), ca.horzcat(h[1, :] + lever * h[2, :], 0.0),
        ca.DM([[0.0, 0.0, 0.0, 1.0]]),
    )  # fmt: skip
    z = ca.vertcat(sums[0] - offset[0], sums[1] - offset[1] - lever * offset[2], rate)
    R = r_scale * ca.diag(ca.DM([s.force_noise**2, s.force_noise**2, s.gyro_noise**2]))
    x, P = update(x, P, z, H, R, ca.vertcat(sums_valid, rate_valid))
    fy, G = wheel_lateral_forces(x[0:3], shares)  # the shares of the predicted forces
    fy_std = ca.sqrt(ca.fmax(ca.diag(ca.mtimes([G, P[0:3, 0:3], G.T])), 0.0))

    core_next = ca.vertcat(
        *observers, x, ca.reshape(P, 16, 1),
        _select(spins_valid, spin, last_spin), fx,
        ca.fmax(started, inputs_valid), 1.0, ca.fmax(core[CORE.spin_seen], spins_valid),
    )  # fmt: skip
    return ca.Function(
        "tyre_core",
        [core, wheels, wheels_valid, sums, sums_valid, rate, rate_valid, loads, dt, observer],
        [core_next, fx, fx_std, fy, fy_std, high_slip],
        list(CORE_INPUTS),
        list(CORE_OUTPUTS),
    )
