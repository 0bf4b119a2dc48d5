r"""Method E, quarter-car tyre-force observer after Cheon et al. (Siegloff & Choi §IV-B, [12]).

Per corner, the unsprung-mass balance of the quarter car
(:func:`wheelload.models.family.quarter_car.tyre_load_function`),

.. math:: F = z(d, v) + m_u a_u, \qquad \ddot d = a_u - a_s,

with :math:`z` the suspension load from the measured travel and rate: by
default the KF's pseudo-measurement with the vehicle file's model terms
(links, tyre forces, stops; the hub accelerometers' unsprung term is left
out, the observer estimates :math:`a_u` itself), with
``suspension=SuspensionModel.PAPER`` eq. 9 alone (static load, spring,
damper, anti-roll bar; :mod:`~wheelload.estimators.family.suspension_model`), the unsprung vertical
acceleration :math:`a_u` an unknown input (random walk), and the body
corner's vertical acceleration :math:`a_s` reconstructed from the body IMU
(:func:`wheelload.models.body_attitude.corner_vertical_acceleration`:
:math:`a_z - g - x_i \dot\omega_y + y_i \dot\omega_x`), the angular
accelerations by differencing the gyro rates (zero when the log has no
rates). A discrete observer on the measured compression rate :math:`v`,

.. math::
    v^- = \hat v + \Delta t\,(\hat a_u - a_s), \quad
    \hat v^+ = v^- + k_1 (v - v^-), \quad \hat a_u^+ = \hat a_u + k_2 (v - v^-), \\
    k_1 = 1 - \lambda^2, \quad k_2 = (1 - \lambda)^2 / \Delta t, \quad
    \lambda = e^{-2\pi f_o \Delta t}, \quad \hat F = z + m_u \hat a_u,

places both poles of the error dynamics at :math:`\lambda` (bandwidth
:math:`f_o`, :data:`OBSERVER_BANDWIDTH`).

Adaptations (the main paper gives no equations for E and [12] is not in
our library): the observer form, its split :math:`F = z + m_u a_u` (observing
only the unsprung inertia, so the observer's lag does not delay the
suspension load) and its pole placement are ours; corner
inputs are reconstructed from the body IMU and suspension signals as the
main paper describes; the four corners run independently. A corner with a
missing travel or rate, or a missing vertical acceleration, holds its
observer state and is flagged. No standard deviation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import StepSymbols, hold, step_function, step_symbols
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import suspension_loads, suspension_mask
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models import ModelParameters, Vehicle
from wheelload.models.body_attitude import corner_vertical_acceleration
from wheelload.models.family.quarter_car import unsprung_balance

OBSERVER_BANDWIDTH = 25.0  # Hz, both poles: above the wheel-hop mode (~14 Hz), below Nyquist
#: v_hat[4], a_u_hat[4], previous rates[3], previous rates valid, last F_hat[4]
FRONT_END_STATES = 16
FRONT_END_CONSTANTS = 13  # m_u[4], corner x[4], corner y[4] from the IMU, bandwidth


def unsprung_masses(vehicle: Vehicle) -> np.ndarray:
    """Unsprung mass of each corner [kg], order FL, FR, RL, RR (half the axle's)."""
    m = vehicle.mass
    return np.array([m.unsprung_front, m.unsprung_front, m.unsprung_rear, m.unsprung_rear]) / 2


def corner_geometry(vehicle: Vehicle) -> np.ndarray:
    """Unsprung mass [kg] and position relative to the IMU (x, y) [m] of each corner (12 values)."""
    g = vehicle.geometry
    imu = np.asarray(g.imu_position, float)
    x = np.array([g.lf, g.lf, -g.lr, -g.lr]) - imu[0]
    y = np.array([g.track_front, -g.track_front, g.track_rear, -g.track_rear]) / 2 - imu[1]
    return np.concatenate([unsprung_masses(vehicle), x, y])


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
    positions = [(c[4 + i], c[8 + i]) for i in range(4)]
    a_s = corner_vertical_acceleration(sym.acc[2], omega_dot[0], omega_dot[1], positions)
    return a_s, rate_state


def unsprung_acceleration(F, z, m_u, corner: int):
    """The unsprung acceleration of ``corner`` that gives tyre load ``F`` on suspension load ``z``.

    Solves :func:`~wheelload.models.family.quarter_car.unsprung_balance` (affine in
    ``a_u``) with its value at ``a_u = 0`` and its Jacobian.
    """
    a = ca.SX.sym("a_u", 4)
    loads = unsprung_balance(z, a, m_u)
    base = ca.substitute(loads, a, ca.DM.zeros(4))
    slope = ca.substitute(ca.jacobian(loads, a), a, ca.DM.zeros(4))
    return (F - base[corner]) / slope[corner, corner]


def front_end(sym: StepSymbols, s: ca.SX, c: ca.SX, model: SuspensionModel):
    """One observer step of the four corners: ``(s_next, F_hat, used)`` (module docstring)."""
    v_hat, a_u, F_held = s[0:4], s[4:8], s[12:16]
    m_u, bandwidth = c[0:4], c[12]
    a_s, rate_state = body_corner_accelerations(sym, s[8:12], c)
    lam = ca.exp(-2.0 * ca.pi * bandwidth * sym.dt)
    k1 = 1.0 - lam**2
    k2 = (1.0 - lam) ** 2 / sym.dt
    # Compression kinematics: d'' = a_u - a_s (unsprung minus body-corner acceleration).
    v_pred = v_hat + sym.dt * (a_u - a_s)
    innovation = sym.v - v_pred
    a_u_new = a_u + k2 * innovation
    z = suspension_loads(model, sym.u, sym.valid, sym.p_vector, unsprung_inertia=False)
    F = unsprung_balance(z, a_u_new, m_u)
    # Needs the corner's travel and rate (and the bar partner's travel) and a_z; rates optional.
    ok = suspension_mask(sym.u_raw, sym.valid, sym.p_vector) * sym.dt_ok * sym.mask(sym.acc[2])
    v_new = hold(ok, v_pred + k1 * innovation, v_hat)
    F_new = hold(ok, F, F_held)
    return ca.vertcat(v_new, hold(ok, a_u_new, a_u), rate_state, F_new), F_new, ok


@functools.cache
def quarter_car_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state and constants of :func:`front_end`; loads = observed tyre loads."""
    sym = step_symbols(FRONT_END_STATES, FRONT_END_CONSTANTS)
    s_next, F, used = front_end(sym, sym.s, sym.c, model)
    return step_function("wheelload_quarter_car_step", model, sym, s_next, F, ca.SX.zeros(4), used)


class QuarterCarObserver(FamilyMethod):
    """Method E: four independent quarter-car tyre-force observers (module docstring)."""

    name = "E quarter-car observer"
    has_std = False

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        bandwidth: float = OBSERVER_BANDWIDTH,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        self.bandwidth = bandwidth
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return quarter_car_step(self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        return (front_end_initial(self.parameters),)

    def constants(self) -> np.ndarray:
        return corner_constants(self.vehicle, self.bandwidth)


@dataclass(frozen=True, kw_only=True)
class QuarterCarOptions:
    """Options of methods E and E+C (``build("E", vehicle, **options)``)."""

    bandwidth: float = OBSERVER_BANDWIDTH  # both observer poles [Hz]


INFO = MethodInfo(
    name="E",
    description="quarter-car tyre-force observer per corner, inputs from body IMU + suspension",
    reference="Siegloff & Choi §IV-B method E; Cheon, Choi, Nam & Oh 2024",
    build=QuarterCarObserver,
    options=QuarterCarOptions,
    model_choice=True,
)
