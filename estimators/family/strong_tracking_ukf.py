r"""Method F, per-corner strong-tracking UKF after Ding et al. (Siegloff & Choi §IV-B, [1]).

Per corner, state :math:`x = [d, v, F]` (compression, compression rate,
tyre normal load), measurements :math:`y = [d, v]`, and the quarter-car
process (the unsprung balance of :func:`wheelload.models.family.quarter_car.unsprung_balance`
solved for the unsprung acceleration)

.. math:: \dot d = v, \quad \dot v = \frac{F - z(d, v)}{m_u} - a_s, \quad \dot F = w_F

with the nonlinear suspension load :math:`z` (asymmetric damper; the
anti-roll bar with the partner wheel's measured travel; by default the KF's
full pseudo-measurement with the vehicle file's terms but the hub
accelerometers' unsprung term, with ``suspension=SuspensionModel.PAPER``
eq. 9 alone, :mod:`~wheelload.estimators.family.suspension_model`) and the body
corner acceleration :math:`a_s` reconstructed from the IMU as in method E.
Prediction by the unscented transform (:mod:`.unscented`) of a fourth-order
Runge-Kutta step over :math:`\Delta t`; :math:`Q = \mathrm{diag}(q)\,\Delta t`.
Strong tracking (Zhou's suboptimal fading factor): with the innovation
:math:`\gamma_k = y_k - H x^-_k`,

.. math::
    V_k = \frac{\rho V_{k-1} + \gamma_k \gamma_k^\top}{1 + \rho}, \quad
    \lambda_k = \min\Big(\lambda_{max}, \max\Big(1,
        \frac{\mathrm{tr}(V_k - \beta R)}{\mathrm{tr}(H \bar P^-_k H^\top)}\Big)\Big), \quad
    P^-_k = \lambda_k \bar P^-_k + Q

(:math:`\bar P^-` the transformed covariance before :math:`Q`). The
measurement is linear, so the update is the Joseph-form Kalman update of
:mod:`wheelload.estimators.kernels.kalman` (what the UKF update gives for a linear
measurement).

Adaptations ([1] is not in our library; the main paper names only the
filter and its measurements): the state, process model, noise levels
(:data:`PROCESS_NOISE`, :data:`MEASUREMENT_NOISE`, the load's random walk is
the vehicle file's KF process noise) and strong-tracking constants
(:data:`FORGETTING`, :data:`WEAKENING`, :data:`MAX_FADING`) are ours;
:math:`V_0 = R`. A corner with a missing travel, rate or vertical
acceleration holds its state and is flagged.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import hold, step_function, step_symbols
from wheelload.estimators.family.quarter_car import (
    body_corner_accelerations,
    corner_geometry,
    unsprung_acceleration,
)
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import suspension_loads, suspension_mask
from wheelload.estimators.family.unscented import sigma_points, unscented_transform
from wheelload.estimators.kernels.kalman import sequential_update, symmetrise
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models import Vehicle

#: Process noise densities of d [m^2/s] and v [(m/s)^2/s]: unmodelled corner kinematics, about
#: 0.5 m/s^2 of body-corner acceleration error at 100 Hz ((0.5 * 0.01)^2 / 0.01).
PROCESS_NOISE = (1e-8, 2.5e-3)
#: Per-sample variances of the measured d [m^2] and v [(m/s)^2]: a travel sensor of 0.1 mm
#: (linearity) and its backward-difference rate, about 3 mm/s at 100 Hz.
MEASUREMENT_NOISE = (1e-8, 1e-5)
FORGETTING = 0.95  # rho
WEAKENING = 1.0  # beta
MAX_FADING = 20.0  # lambda_max; 1 turns strong tracking off
INITIAL_STD = (0.05, 1.0)  # m, m/s: the first sample sets d and v, not F
CORNER_STATES = 3 + 9 + 4  # x, P (column-major), V (column-major)
N_STATES = 4 * CORNER_STATES + 4  # + previous rates[3], previous rates valid
N_CONSTANTS = 12 + 3 + 2 + 3  # corner geometry, q, r, (rho, beta, lambda_max)
H = ca.DM([[1, 0, 0], [0, 1, 0]])


def _process(sym, corner: int, m_u, a_s, model: SuspensionModel):
    """Continuous corner dynamics ``f(x)`` with the other wheels' travel and rate as measured."""

    def f(x):
        d = ca.vertcat(*[x[0] if i == corner else sym.d[i] for i in range(4)])
        v = ca.vertcat(*[x[1] if i == corner else sym.v[i] for i in range(4)])
        z = suspension_loads(model, sym.u, sym.valid, sym.p_vector, d, v, unsprung_inertia=False)
        a_u = unsprung_acceleration(x[2], z, m_u, corner)
        return ca.vertcat(x[1], a_u - a_s, 0)

    return f


def _rk4(f, x, dt):
    k1 = f(x)
    k2 = f(x + dt / 2 * k1)
    k3 = f(x + dt / 2 * k2)
    k4 = f(x + dt * k3)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def corner_update(sym, s, corner: int, a_s, c, model: SuspensionModel):
    """One strong-tracking UKF step of one corner: ``(s_next, F, std_F)``."""
    x, P, V = s[0:3], ca.reshape(s[3:12], 3, 3), ca.reshape(s[12:16], 2, 2)
    m_u = c[0:4]
    q, r = c[12:15], c[15:17]
    rho, beta, max_fading = c[17], c[18], c[19]
    f = _process(sym, corner, m_u, a_s, model)
    points = [_rk4(f, point, sym.dt) for point in sigma_points(x, P)]
    x_pred, P_bar = unscented_transform(points)
    R = ca.diag(r)
    y = ca.vertcat(sym.d[corner], sym.v[corner])
    gamma = y - ca.mtimes(H, x_pred)
    V_new = (rho * V + ca.mtimes(gamma, gamma.T)) / (1 + rho)
    ratio = ca.trace(V_new - beta * R) / ca.trace(ca.mtimes([H, P_bar, H.T]))
    fading = ca.fmin(max_fading, ca.fmax(1, ratio))
    P_pred = symmetrise(fading * P_bar + ca.diag(q) * sym.dt)
    x_new, P_new = sequential_update(x_pred, P_pred, y, H, r)
    s_next = ca.vertcat(x_new, ca.vec(P_new), ca.vec(V_new))
    return s_next, x_new[2], ca.sqrt(ca.fmax(P_new[2, 2], 0))


@functools.cache
def strong_tracking_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state = 4 corners (x, P, V) and the previous rates; constants see module."""
    sym = step_symbols(N_STATES, N_CONSTANTS)
    a_s, rate_state = body_corner_accelerations(sym, sym.s[4 * CORNER_STATES :], sym.c)
    z_mask = suspension_mask(sym.u_raw, sym.valid, sym.p_vector) * sym.dt_ok
    ok = z_mask * sym.mask(sym.acc[2])
    states, loads, stds = [], [], []
    for i in range(4):
        s_i = sym.s[i * CORNER_STATES : (i + 1) * CORNER_STATES]
        s_new, F, std = corner_update(sym, s_i, i, a_s[i], sym.c, model)
        states.append(hold(ca.repmat(ok[i], CORNER_STATES, 1), s_new, s_i))
        loads.append(ca.if_else(ok[i], F, s_i[2]))
        stds.append(ca.if_else(ok[i], std, ca.sqrt(ca.fmax(s_i[3 + 8], 0))))
    return step_function(
        "wheelload_strong_tracking_ukf_step",
        model,
        sym,
        ca.vertcat(*states, rate_state),
        ca.vertcat(*loads),
        ca.vertcat(*stds),
        ok,
    )


class StrongTrackingUKF(FamilyMethod):
    """Method F: four strong-tracking UKFs on compression and rate (module docstring)."""

    name = "F strong-tracking UKF"
    has_std = True

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        max_fading: float = MAX_FADING,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        if not max_fading >= 1:
            raise ValueError(f"max_fading must be >= 1, got {max_fading}")
        self.max_fading = max_fading
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return strong_tracking_step(self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        initial_std = self.vehicle.filter.initial_std
        P0 = np.diag([INITIAL_STD[0] ** 2, INITIAL_STD[1] ** 2, initial_std**2])
        corners = [
            np.concatenate(
                [[0.0, 0.0, load], P0.ravel(order="F"), np.diag(MEASUREMENT_NOISE).ravel()]
            )
            for load in self.parameters.static()
        ]
        return (np.concatenate([*corners, np.zeros(4)]),)

    def constants(self) -> np.ndarray:
        q = [*PROCESS_NOISE, self.vehicle.filter.process_noise_density]
        fading = [FORGETTING, WEAKENING, self.max_fading]
        return np.concatenate([corner_geometry(self.vehicle), q, MEASUREMENT_NOISE, fading])


@dataclass(frozen=True, kw_only=True)
class StrongTrackingOptions:
    """Options of method F (``build("F", vehicle, **options)``)."""

    max_fading: float = MAX_FADING  # largest fading factor (>= 1) of the strong tracking


INFO = MethodInfo(
    name="F",
    description="strong-tracking UKF per corner on suspension compression and rate",
    reference="Siegloff & Choi §IV-B method F; Ding, Wang, Zhang & Liu 2022",
    build=StrongTrackingUKF,
    options=StrongTrackingOptions,
    model_choice=True,
)
