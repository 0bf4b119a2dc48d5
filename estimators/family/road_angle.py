r"""Road-angle Kalman filter (Jiang et al., road-angle paper §II-III, eq. 4-18).

A linear KF on the 14-state model of :mod:`wheelload.models.road_angle`
(eq. 12-15), discretised exactly for each sample interval (matrix exponential,
Van Loan for the process noise), measured (eq. 16-17) by

- roll and pitch relative to the road from the four travels (eq. 7),
- roll and pitch rate from the gyro (rows skipped when the log has no rates),
- the four loads from the suspension pseudo-measurement
  (:mod:`wheelload.models.suspension`; the paper lists the loads in its output
  vector without saying what measures them),
- the specific force rotated into the road frame with the eq. 7 angles
  (eq. 4-5).

Road grade and bank (reported by :meth:`RoadAngleKF.run_with_road_angles`,
radians, grade > 0 uphill, bank > 0 with the left edge higher) separate
gravity from motion in the road-frame specific force (§II-A, eq. 2):

.. math:: \sin\gamma = \frac{a_{xr} - \dot v_x}{g}, \quad
          \sin\beta = \frac{a_{yr} - v_x \omega_z}{g \cos\gamma}

with :math:`\dot v_x` from a filtered derivative of the speed and
:math:`\omega_z` the yaw rate (zero without rates). The lateral slip
acceleration :math:`\dot v_y` is not measured (it reaches 1.8 m/s^2, 10 deg
of bank, in the banked chicane); it averages out over a manoeuvre, so the
bank is low-passed by two first-order stages of 2.5 s, the grade (whose
motion term :math:`\dot v_x` is measured) by one of 1 s. Both filters start
at the first sample's value.

Per-sample numpy (a 14-state filter): about 1-2 s for a 90 s lap at 100 Hz.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.linalg

from wheelload.estimators.protocol import samples
from wheelload.estimators.registry import MethodInfo
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import MAX_INTERVAL, Sample, sample_intervals
from wheelload.models import (
    GRAVITY,
    ModelParameters,
    Vehicle,
    equilibrium_function,
    suspension_function,
)
from wheelload.models.body_attitude import attitude_function
from wheelload.models.road_angle import STATE_NAMES, BodyInertia, road_angle_model

N = len(STATE_NAMES)
#: Measured states (eq. 16): roll, roll rate, pitch, pitch rate, 4 loads, 3 road-frame
#: accelerations.
MEASURED = (0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 12)

DEFAULT_INERTIA = BodyInertia()


@dataclass(frozen=True, kw_only=True)
class RoadAngleTuning:
    """Noise of the road-angle KF (1 sigma or densities) and the road-angle filters."""

    angle_std: float = 2e-3  # rad, eq. 7 angle against the body's attitude
    rate_std: float = 0.02  # rad/s, gyro against the road-relative rate
    acceleration_std: float = 0.1  # m/s^2
    angle_acceleration_density: float = 25.0  # (rad/s^2)^2 s, unmodelled torques
    jerk_density: float = 400.0  # (m/s^3)^2 s ... per s: random jerk rate of a_r
    speed_derivative_time_constant: float = 0.2  # s
    grade_time_constant: float = 1.0  # s, first-order low-pass of the grade
    bank_time_constant: float = 2.5  # s, each stage of a second-order low-pass of the bank

    def __post_init__(self) -> None:
        for key in (
            "angle_std", "rate_std", "acceleration_std", "angle_acceleration_density",
            "jerk_density", "speed_derivative_time_constant", "grade_time_constant",
            "bank_time_constant",
        ):  # fmt: skip
            if not getattr(self, key) > 0:
                raise ValueError(f"road-angle tuning '{key}' must be > 0, got {getattr(self, key)}")


@dataclass(frozen=True, kw_only=True)
class RoadAngleState:
    x: np.ndarray  # (14,)
    P: np.ndarray  # (14, 14)
    speed: float  # previous speed (NaN before the first sample)
    speed_rate: float  # filtered dv/dt
    grade: float  # rad (NaN before the first sample)
    bank: float  # rad, output of the second low-pass stage
    bank_stage: float  # rad, first low-pass stage


class RoadAngleKF:
    """14-state road-angle KF; loads with standard deviations, and road grade and bank."""

    name = "road-angle KF"

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        inertia: BodyInertia = DEFAULT_INERTIA,
        tuning: RoadAngleTuning = RoadAngleTuning(),
    ) -> None:
        self.vehicle = vehicle
        self.inertia = inertia
        self.tuning = tuning
        self.parameters = ModelParameters.from_vehicle(vehicle)
        self.p = self.parameters.vector()
        model = road_angle_model(vehicle, inertia)
        x = ca.SX.sym("x", N)
        xdot, loads = model(x)
        self.A = np.asarray(ca.DM(ca.jacobian(xdot, x)), float)
        self._loads_of = ca.Function("road_angle_loads", [x], [loads])
        self._attitude = attitude_function(vehicle)
        self._suspension = suspension_function()
        self._equilibrium = equilibrium_function()
        self.H = np.zeros((len(MEASURED), N))
        self.H[np.arange(len(MEASURED)), MEASURED] = 1.0
        filt = vehicle.filter
        self._noise = np.zeros(N)  # process noise densities per state
        self._noise[[1, 3]] = tuning.angle_acceleration_density
        self._noise[4:8] = filt.process_noise_density
        self._noise[[9, 11, 13]] = tuning.jerk_density
        self._suspension_density = filt.suspension_noise_density
        self._initial_std = filt.initial_std

    def initial_state(self) -> RoadAngleState:
        """Level road, static loads (eq. 14), 1 g vertical specific force."""
        x = np.zeros(N)
        x[4:8] = self.parameters.static()
        x[12] = GRAVITY
        std = np.zeros(N)
        std[[0, 2]] = 0.02
        std[[1, 3]] = 0.1
        std[4:8] = self._initial_std
        std[[8, 10, 12]] = 2.0
        std[[9, 11, 13]] = 5.0
        return RoadAngleState(
            x=x, P=np.diag(std**2), speed=math.nan, speed_rate=0.0, grade=math.nan,
            bank=math.nan, bank_stage=math.nan,
        )  # fmt: skip

    @functools.lru_cache(maxsize=16)  # noqa: B019  (one model per sample interval)
    def _discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """``(F, Q)`` over ``dt``: exact transition, Van Loan process noise."""
        M = np.zeros((2 * N, 2 * N))
        M[:N, :N] = -self.A * dt
        M[:N, N:] = np.diag(self._noise) * dt
        M[N:, N:] = self.A.T * dt
        E = scipy.linalg.expm(M)
        F = E[N:, N:].T
        Q = F @ E[:N, N:]
        return F, 0.5 * (Q + Q.T)

    def _measurement(self, sample: Sample, dt: float):
        """Measured vector (eq. 16), its variances, and which rows are usable."""
        d, v = np.asarray(sample.d, float), np.asarray(sample.v, float)
        acc = np.asarray(sample.acc, float)
        rates = np.full(3, np.nan) if sample.rates is None else np.asarray(sample.rates, float)
        roll, pitch, acc_road = (
            np.asarray(m, float).ravel()
            for m in self._attitude(np.nan_to_num(d), np.nan_to_num(acc))
        )
        loads = np.asarray(self._suspension(np.nan_to_num(d), np.nan_to_num(v), self.p)).ravel()
        z = np.concatenate([[roll[0], rates[0], pitch[0], rates[1]], loads, acc_road])
        travel_ok = bool(np.all(np.isfinite(d)))
        acc_ok = travel_ok and bool(np.all(np.isfinite(acc)))
        ok = np.array(
            [travel_ok, np.isfinite(rates[0]), travel_ok, np.isfinite(rates[1])]
            + list(np.isfinite(d) & np.isfinite(v))
            + [acc_ok] * 3
        )
        t = self.tuning
        variance = np.concatenate(
            [
                [t.angle_std**2, t.rate_std**2, t.angle_std**2, t.rate_std**2],
                np.full(4, self._suspension_density / dt),
                np.full(3, t.acceleration_std**2),
            ]
        )
        return np.where(ok, z, 0.0), variance, ok

    def step(
        self, state: RoadAngleState, sample: Sample, dt: float
    ) -> tuple[RoadAngleState, Estimate]:
        """Predict, update with the usable rows, then the road angles."""
        acc = np.asarray(sample.acc, float)
        if not (np.isfinite(dt) and 0.0 < dt < MAX_INTERVAL):
            flags = int(StepFlag.STEP_REJECTED) | 0x7F
            return state, self._estimate(state, acc, sample.vx, flags)
        F, Q = self._discrete(round(float(dt), 7))
        x = F @ state.x
        P = F @ state.P @ F.T + Q
        z, variance, ok = self._measurement(sample, dt)
        H, R = self.H[ok], np.diag(variance[ok])
        if H.shape[0]:
            S = H @ P @ H.T + R
            K = np.linalg.solve(S, H @ P).T
            x = x + K @ (z[ok] - H @ x)
            I_KH = np.eye(N) - K @ H
            P = I_KH @ P @ I_KH.T + K @ R @ K.T  # Joseph form
        P = 0.5 * (P + P.T)
        speed, speed_rate, grade, bank_stage, bank = self._road_angles(state, x, sample, dt)
        flags = sum(int(list(StepFlag)[i]) for i in range(4) if not ok[4 + i])
        new = RoadAngleState(
            x=x, P=P, speed=speed, speed_rate=speed_rate, grade=grade, bank=bank,
            bank_stage=bank_stage,
        )  # fmt: skip
        return new, self._estimate(new, acc, sample.vx, flags)

    def _road_angles(self, state: RoadAngleState, x, sample: Sample, dt: float):
        """Filtered speed derivative, then grade and bank from eq. (2) in the road frame."""
        t = self.tuning
        vx = float(sample.vx)
        speed_rate = state.speed_rate
        if np.isfinite(vx) and np.isfinite(state.speed):
            blend = math.exp(-dt / t.speed_derivative_time_constant)
            speed_rate = blend * speed_rate + (1 - blend) * (vx - state.speed) / dt
        speed = vx if np.isfinite(vx) else state.speed
        yaw_rate = 0.0 if sample.rates is None else float(sample.rates[2])
        yaw_rate = yaw_rate if np.isfinite(yaw_rate) else 0.0
        grade_now = math.asin(float(np.clip((x[8] - speed_rate) / GRAVITY, -1, 1)))
        lateral = (x[10] - (speed if np.isfinite(speed) else 0.0) * yaw_rate) / (
            GRAVITY * math.cos(grade_now)
        )
        bank_now = math.asin(float(np.clip(lateral, -1, 1)))
        if math.isnan(state.grade):  # first sample: the filters start at the first values
            return speed, speed_rate, grade_now, bank_now, bank_now
        blend = math.exp(-dt / t.grade_time_constant)
        grade = blend * state.grade + (1 - blend) * grade_now
        blend = math.exp(-dt / t.bank_time_constant)
        bank_stage = blend * state.bank_stage + (1 - blend) * bank_now
        bank = blend * state.bank + (1 - blend) * bank_stage
        return speed, speed_rate, grade, bank_stage, bank

    def _estimate(self, state: RoadAngleState, acc, vx, flags: int) -> Estimate:
        loads = state.x[4:8]
        std = np.sqrt(np.maximum(np.diag(state.P)[4:8], 0.0))
        if np.all(np.isfinite(acc)) and np.isfinite(vx):
            A, b = (np.asarray(m, float) for m in self._equilibrium(acc, vx, self.p))
            residual = b.ravel() - A @ loads
        else:
            residual = np.zeros(3)
            flags |= int(StepFlag.VERTICAL_SKIPPED | StepFlag.PITCH_SKIPPED | StepFlag.ROLL_SKIPPED)
        return Estimate(
            t=np.array([np.nan]),
            loads=loads.reshape(1, 4).copy(),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=np.array([flags], dtype=np.int64),
        )

    def run_with_road_angles(self, signals: Signals) -> tuple[Estimate, np.ndarray]:
        """The estimate and the road grade and bank [rad] of every sample, shape (n, 2)."""
        state = self.initial_state()
        rows, angles = [], np.empty((len(signals), 2))
        for k, (sample, dt) in enumerate(zip(samples(signals), sample_intervals(signals.t))):
            state, estimate = self.step(state, sample, float(dt))
            rows.append(estimate)
            angles[k] = state.grade, state.bank
        return Estimate(
            t=signals.t.copy(),
            loads=np.concatenate([r.loads for r in rows]),
            std=np.concatenate([r.std for r in rows]),
            residual=np.concatenate([r.residual for r in rows]),
            flags=np.concatenate([r.flags for r in rows]),
        ), angles

    def run(self, signals: Signals) -> Estimate:
        """Every sample through :meth:`step` from a fresh state."""
        return self.run_with_road_angles(signals)[0]


INFO = MethodInfo(
    name="road-angle",
    description="14-state KF with roll/pitch dynamics and road-frame accelerations; grade, bank",
    reference="Jiang et al., road-angle paper §II-III, eq. 4-18",
    build=RoadAngleKF,
)
