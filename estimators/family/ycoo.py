r"""Youla controller-output observer, YCOO (ycoo-umvf paper §3, eq. 13-15), per corner.

The observer's estimate of the tyre load is the first row of the Youla
transfer function (eq. 14) applied to the measurements
:math:`y = [a_s, \tilde q]`:

.. math::
    \hat{\tilde f}_z = F(s)\,\big[m_u a_s + (m_u s^2 + b_s s + k_s)\,\tilde q\big], \quad
    F(s) = \frac{\omega_0^2}{(s^2 + 2\zeta\omega_0 s + \omega_0^2)(\tau s + 1)^2}

i.e. eq. (15): the unsprung balance (eq. 3-4) seen through the closed-loop
filter :math:`M_T` (eq. 8). Defaults: bandwidth :math:`\omega_0 = 2\pi\,30`
Hz and :math:`\zeta = 1/\sqrt2` (the paper's); the paper does not give
:math:`\tau` ("additional poles to make the controller proper"): here
:math:`\tau = 1/(5\omega_0)`, poles at 150 Hz.

Adaptations, each kept as small as the signals allow:

- :math:`k_s \tilde q + b_s \dot{\tilde q}` is the suspension pseudo-measurement of
  :mod:`wheelload.models.suspension.pseudo_measurement` (spring, asymmetric damper, anti-roll
  bar, static load) evaluated on the filtered travel and its filtered
  derivative; with a linear damper and no bar it is exactly eq. (14). The
  paper assumes no anti-roll bar (§2); ours has one, and it is kept. By
  default the pseudo-measurement is the KF's full one with the vehicle
  file's model terms (links, tyre forces, stops; not the hub accelerometers'
  unsprung term, which the observer estimates itself); with
  ``suspension=SuspensionModel.PAPER``, eq. 9 alone
  (:mod:`~wheelload.estimators.family.suspension_model`).
- :math:`a_s` per corner is reconstructed from the body IMU:
  :math:`a_z - g + \dot\omega_x y_i - \dot\omega_y x_i` with
  :math:`F(s)\,s\,\omega` as the filtered angular acceleration (zero when
  the log has no rates) (:func:`~wheelload.models.body_attitude.corner_vertical_acceleration`).
- The filters start in steady state on the first sample (the paper leaves
  its observers uninitialised to show their 0.1 s convergence; a start from
  zero travel costs a 600 N transient on a log that begins at speed).
- Discretised with the interval as an input (:mod:`wheelload.estimators.kernels.discretise`),
  the hold chosen per channel for the magnitude closest to eq. (14) at the
  logs' 100 Hz: first-order hold on the travels (FOH's sinc^2 droop is
  partly offset by the aliased :math:`m_u s^2` term), Tustin on the
  accelerations and rates (FOH alone droops 1.1 dB at 20 Hz). Both paths are
  within 1 dB of eq. (14) up to 20 Hz (tests/equivalence/test_ycoo.py).

The filter is realised as a cascade (two first-order lags, then the
second-order section) with states
:math:`[p_1, p_2, y, \dot y / \omega_0]`, which gives :math:`y, \dot y, \ddot y`
without differentiating. The step is one CasADi Function; ``run`` loops it
in compiled C. No standard deviation (``has_std=False``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import flag_sum, step_name
from wheelload.estimators.family.quarter_car import unsprung_masses
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import equilibrium, suspension_loads
from wheelload.estimators.kernels.discretise import first_order_hold, trapezoidal
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS, ModelParameters, Vehicle
from wheelload.models.body_attitude import corner_positions, corner_vertical_acceleration
from wheelload.models.conventions import GRAVITY
from wheelload.models.family.quarter_car import unsprung_balance
from wheelload.models.input_validity import interval_is_valid, sanitise

#: Filtered channels: four travels, vertical specific force minus g, roll and pitch rate.
CHANNELS = 7
STATES = 4  # per channel


@dataclass(frozen=True, kw_only=True)
class YcooSettings:
    """Closed-loop shape of eq. (8): bandwidth [Hz], damping ratio, extra-pole time constant."""

    bandwidth: float = 30.0
    damping: float = 1.0 / math.sqrt(2.0)
    pole_ratio: float = 5.0  # tau = 1 / (pole_ratio * omega_0)

    def __post_init__(self) -> None:
        for key in ("bandwidth", "damping", "pole_ratio"):
            if not getattr(self, key) > 0:
                raise ValueError(f"YCOO setting '{key}' must be > 0, got {getattr(self, key)}")

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.bandwidth

    @property
    def tau(self) -> float:
        return 1.0 / (self.pole_ratio * self.omega)


def filter_matrices(settings: YcooSettings) -> tuple[np.ndarray, np.ndarray]:
    r"""Continuous ``(A, B)`` of :math:`F(s)` with states :math:`[p_1, p_2, y, \dot y/\omega_0]`."""
    w, z, tau = settings.omega, settings.damping, settings.tau
    A = np.array(
        [
            [-1 / tau, 0, 0, 0],
            [1 / tau, -1 / tau, 0, 0],
            [0, 0, 0, w],
            [0, w, -w, -2 * z * w],
        ]
    )
    B = np.array([[1 / tau], [0], [0], [0]])
    return A, B


def filter_outputs(X, settings: YcooSettings):
    r"""Rows :math:`y, \dot y, \ddot y` of the filter states ``X`` (4 x channels)."""
    w, z = settings.omega, settings.damping
    y = X[2, :]
    y_dot = w * X[3, :]
    y_ddot = w * w * (X[1, :] - X[2, :]) - 2 * z * w * y_dot
    return y, y_dot, y_ddot


def step_function(
    vehicle: Vehicle, settings: YcooSettings, model: SuspensionModel = DEFAULT_MODEL
) -> ca.Function:
    """``(X, u_prev, u, u_valid, dt, p, m_u) -> (X, u_prev, loads, std, residual, flags)``."""
    X = ca.SX.sym("X", STATES * CHANNELS)
    memory = ca.SX.sym("u_prev", CHANNELS + 1)  # previous channel inputs, started flag
    started = memory[CHANNELS]
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", len(ModelParameters.names()))
    mu = ca.SX.sym("m_u", 4)

    u = sanitise(u_raw, valid)
    u_prev_stored = memory[0:CHANNELS]
    d, acc, rates = u[0:4], u[8:11], u[12:15]
    channel = ca.vertcat(d, acc[2] - GRAVITY, rates[0], rates[1])
    channel_valid = ca.vertcat(valid[0:4], valid[10], valid[12], valid[13])
    # A missing channel holds its last value (the filter sees a constant input).
    held = ca.vertcat(
        *[ca.if_else(channel_valid[i], channel[i], u_prev_stored[i]) for i in range(CHANNELS)]
    )
    # The first sample starts every channel's filter in steady state on its input.
    u_prev = ca.if_else(started, u_prev_stored, held)
    steady = ca.vertcat(held.T, held.T, held.T, ca.DM.zeros(1, CHANNELS))
    ok = interval_is_valid(dt)
    dt_safe = ca.if_else(ok, dt, 1e-3)
    A, B = filter_matrices(settings)
    Xm = ca.if_else(started, ca.reshape(X, STATES, CHANNELS), steady)
    columns = []
    for hold, first, last in ((first_order_hold, 0, 4), (trapezoidal, 4, CHANNELS)):
        Phi, Gamma1, Gamma2 = hold(ca.DM(A), ca.DM(B), dt_safe)
        previous, now = u_prev[first:last].T, held[first:last].T
        columns.append(
            ca.mtimes(Phi, Xm[:, first:last])
            + ca.mtimes(Gamma1, previous)
            + ca.mtimes(Gamma2, now - previous)
        )
    Xn = ca.horzcat(*columns)
    Xn = ca.if_else(ok, Xn, ca.reshape(X, STATES, CHANNELS))
    u_next = ca.if_else(ok, ca.vertcat(held, 1), memory)

    y, y_dot, y_ddot = filter_outputs(Xn, settings)
    positions = corner_positions(vehicle)
    a_s = corner_vertical_acceleration(y[4] + GRAVITY, y_dot[5], y_dot[6], positions)
    a_u = a_s + y_ddot[0:4].T
    z = suspension_loads(model, u, valid, p, y[0:4].T, y_dot[0:4].T, unsprung_inertia=False)
    loads = unsprung_balance(z, a_u, mu)
    A_eq, b_eq = equilibrium(model, u, valid, p)
    residual = b_eq - ca.mtimes(A_eq, loads)
    rejected = 1 - ok
    acc_missing = 1 - valid[8] * valid[9] * valid[10] * valid[11]
    flags = flag_sum(
        [
            (ca.fmax(1 - valid[i], rejected), flag)
            for i, flag in enumerate(StepFlag.update_flags()[:4])
        ]
        + [
            (ca.fmax(1 - valid[10], rejected), StepFlag.VERTICAL_SKIPPED),
            (ca.fmax(acc_missing, rejected), StepFlag.PITCH_SKIPPED),
            (ca.fmax(acc_missing, rejected), StepFlag.ROLL_SKIPPED),
            (rejected, StepFlag.STEP_REJECTED),
        ]
    )
    return ca.Function(
        step_name("wheelload_ycoo_step", model),
        [X, memory, u_raw, valid, dt, p, mu],
        [ca.vec(Xn), u_next, loads, ca.DM.zeros(4), residual, flags],
        ["X", "u_prev", "u", "u_valid", "dt", "p", "m_u"],
        ["X_next", "u_prev_next", "loads", "std", "residual", "flags"],
    )


class Ycoo(FamilyMethod):
    """YCOO tyre-load observer on each corner (eq. 15); compiled loop."""

    name = "YCOO"
    has_std = False

    def __init__(
        self,
        vehicle: Vehicle,
        settings: YcooSettings = YcooSettings(),
        *,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        self.settings = settings
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return step_function(self.vehicle, self.settings, self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        return (np.zeros(STATES * CHANNELS), np.zeros(CHANNELS + 1))

    def constants(self) -> np.ndarray:
        return unsprung_masses(self.vehicle)


@dataclass(frozen=True, kw_only=True)
class YcooOptions:
    """Options of the YCOO (``build("ycoo", vehicle, **options)``)."""

    settings: YcooSettings = YcooSettings()  # controller bandwidth, damping, pole ratio


INFO = MethodInfo(
    name="ycoo",
    description="Youla controller-output observer per corner, 30 Hz, zeta = 1/sqrt(2)",
    reference="ycoo-umvf paper (Energies 2021, 14, 2378) §3, eq. 8-15",
    build=Ycoo,
    options=YcooOptions,
    model_choice=True,
)
