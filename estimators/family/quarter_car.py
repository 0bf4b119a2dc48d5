r"""Method E, quarter-car tyre-force observer after Cheon et al. (Siegloff & Choi §IV-B, [12]).

Per corner, the quarter-car balance of the unsprung mass
(:mod:`wheelload.models.quarter_car`),

.. math:: \ddot d = \frac{F - z(d, v)}{m_u} - a_s,

with the tyre normal load :math:`F = z + w` split into the suspension load
:math:`z` of eq. 9 (from the measured travel and rate) and the unsprung
inertia force :math:`w = m_u \ddot z_u`, an unknown input (random walk);
the body corner's vertical acceleration :math:`a_s` is reconstructed from
the body IMU: :math:`a_s = a_z - g - x_i \dot\omega_y + y_i \dot\omega_x`,
the angular accelerations by differencing the gyro rates (zero when the log
has no rates). A discrete observer on the measured compression rate
:math:`v`,

.. math::
    v^- = \hat v + \Delta t\,(\hat w/m_u - a_s), \quad
    \hat v^+ = v^- + k_1 (v - v^-), \quad \hat w^+ = \hat w + k_2 (v - v^-), \\
    k_1 = 1 - \lambda^2, \quad k_2 = (1 - \lambda)^2 m_u / \Delta t, \quad
    \lambda = e^{-2\pi f_o \Delta t}, \quad \hat F = z + \hat w,

places both poles of the error dynamics at :math:`\lambda` (bandwidth
:math:`f_o`, :data:`OBSERVER_BANDWIDTH`).

Adaptations (the main paper gives no equations for E and [12] is not in
our library): the observer form, its split :math:`F = z + w` (observing
only the unsprung inertia, so the observer's lag does not delay the
suspension load) and its pole placement are ours; corner
inputs are reconstructed from the body IMU and suspension signals as the
main paper describes; the four corners run independently. A corner with a
missing travel or rate, or a missing vertical acceleration, holds its
observer state and is flagged. No standard deviation.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.family.compiled_method import (
    CompiledMethod,
    StepSymbols,
    hold,
    step_function,
    step_symbols,
)
from wheelload.estimators.registry import MethodInfo
from wheelload.models import ModelParameters, Vehicle, suspension_function
from wheelload.models.quarter_car import corner_acceleration_function, quarter_car_function

OBSERVER_BANDWIDTH = 25.0  # Hz, both poles: above the wheel-hop mode (~14 Hz), below Nyquist
#: v_hat[4], w_hat[4], previous rates[3], previous rates valid, last F_hat[4]
FRONT_END_STATES = 16
FRONT_END_CONSTANTS = 13  # m_u[4], corner x[4], corner y[4] from the IMU, bandwidth


def corner_geometry(vehicle: Vehicle) -> np.ndarray:
    """Unsprung mass [kg] and position relative to the IMU (x, y) [m] of each corner (12 values)."""
    g, m = vehicle.geometry, vehicle.mass
    imu = np.asarray(g.imu_position, float)
    x = np.array([g.lf, g.lf, -g.lr, -g.lr]) - imu[0]
    y = np.array([g.track_front, -g.track_front, g.track_rear, -g.track_rear]) / 2 - imu[1]
    m_u = np.array([m.unsprung_front, m.unsprung_front, m.unsprung_rear, m.unsprung_rear]) / 2
    return np.concatenate([m_u, x, y])


def corner_constants(vehicle: Vehicle, bandwidth: float) -> np.ndarray:
    """:func:`corner_geometry` and the observer bandwidth [Hz]."""
    if not bandwidth > 0:
        raise ValueError(f"observer bandwidth must be > 0 Hz, got {bandwidth}")
    return np.concatenate([corner_geometry(vehicle), [bandwidth]])


def front_end_initial(parameters: ModelParameters) -> np.ndarray:
    """Observer at rest on the static loads."""
    return np.concatenate([np.zeros(12), parameters.static()])


def body_angular_acceleration(sym: StepSymbols, previous: ca.SX, previous_ok: ca.SX):
    """Backward difference of the gyro rates; zero without two valid consecutive samples."""
    rates_ok = ca.mmin(sym.mask(sym.rates))
    ok = rates_ok * previous_ok
    omega_dot = ca.if_else(ok, (sym.rates - previous) / sym.dt, ca.DM.zeros(3))
    return omega_dot, ca.vertcat(ca.if_else(rates_ok, sym.rates, previous), rates_ok)


def body_corner_accelerations(sym: StepSymbols, rates: ca.SX, c: ca.SX):
    """Vertical accelerations of the four body corners from the IMU (``c``: corner geometry).

    ``rates`` is the state (previous rates[3], previous valid); returns ``(a_s, next rates)``.
    """
    omega_dot, rate_state = body_angular_acceleration(sym, rates[0:3], rates[3])
    corner = corner_acceleration_function()
    a_s = ca.vertcat(*[corner(sym.acc[2], omega_dot, c[4 + i], c[8 + i]) for i in range(4)])
    return a_s, rate_state


def corner_inputs(sym: StepSymbols, s: ca.SX, c: ca.SX):
    """Suspension loads, body-corner accelerations and their validity for the four corners.

    Returns ``(z, a_s, ok, rate_state)``; ``rate_state`` is the next (rates, rates valid).
    """
    z = suspension_function()(sym.d, sym.v, sym.p_vector)
    a_s, rate_state = body_corner_accelerations(sym, s[8:12], c)
    ok = sym.mask(z) * sym.mask(sym.acc[2])
    return z, a_s, ok, rate_state


def front_end(sym: StepSymbols, s: ca.SX, c: ca.SX):
    """One observer step of the four corners: ``(s_next, F_hat, used)`` (module docstring)."""
    v_hat, w_hat, F_held = s[0:4], s[4:8], s[12:16]
    m_u, bandwidth = c[0:4], c[12]
    z, a_s, ok, rate_state = corner_inputs(sym, s, c)
    lam = ca.exp(-2.0 * ca.pi * bandwidth * sym.dt)
    k1 = 1.0 - lam**2
    k2 = (1.0 - lam) ** 2 * m_u / sym.dt
    balance = quarter_car_function()
    v_pred = ca.vertcat(
        *[v_hat[i] + sym.dt * balance(z[i] + w_hat[i], z[i], a_s[i], m_u[i]) for i in range(4)]
    )
    innovation = sym.v - v_pred
    v_new = hold(ok, v_pred + k1 * innovation, v_hat)
    w_new = hold(ok, w_hat + k2 * innovation, w_hat)
    F_new = hold(ok, z + w_new, F_held)
    return ca.vertcat(v_new, w_new, rate_state, F_new), F_new, ok


@functools.cache
def quarter_car_step() -> ca.Function:
    """Step: state and constants of :func:`front_end`; loads = observed tyre loads."""
    sym = step_symbols(FRONT_END_STATES, FRONT_END_CONSTANTS)
    s_next, F, used = front_end(sym, sym.s, sym.c)
    return step_function("wheelload_quarter_car_step", sym, s_next, F, ca.SX.zeros(4), used)


class QuarterCarObserver(CompiledMethod):
    """Method E: four independent quarter-car tyre-force observers (module docstring)."""

    name = "E quarter-car observer"
    has_std = False

    def __init__(self, vehicle: Vehicle, *, bandwidth: float = OBSERVER_BANDWIDTH) -> None:
        parameters = ModelParameters.from_vehicle(vehicle)
        super().__init__(
            quarter_car_step(),
            parameters.vector(),
            corner_constants(vehicle, bandwidth),
            front_end_initial(parameters),
        )


INFO = MethodInfo(
    name="E",
    description="quarter-car tyre-force observer per corner, inputs from body IMU + suspension",
    reference="Siegloff & Choi §IV-B method E; Cheon, Choi, Nam & Oh 2024",
    build=QuarterCarObserver,
)
