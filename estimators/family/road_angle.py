r"""Road-angle Kalman filter (Jiang et al., road-angle paper §II-III, eq. 4-18).

A linear KF on the 14-state model of :mod:`wheelload.models.family.road_angle`
(eq. 12-15), discretised exactly for each sample interval (matrix exponential,
Van Loan for the process noise), measured (eq. 16-17) by

- roll and pitch relative to the road from the four travels (eq. 7),
- roll and pitch rate from the gyro (rows skipped when the log has no rates),
- the four loads from the suspension pseudo-measurement
  (:mod:`wheelload.models.suspension.pseudo_measurement`; the paper lists the loads in its output
  vector without saying what measures them): by default the KF's own, with
  the vehicle file's model terms, with ``suspension=SuspensionModel.PAPER``
  eq. 9 alone (:mod:`~wheelload.estimators.family.suspension_model`),
- the specific force rotated into the road frame with the eq. 7 angles
  (eq. 4-5).

Road grade and bank (reported by :meth:`RoadAngleKF.run_with_road_angles`,
radians, grade > 0 uphill, bank > 0 with the left edge higher) separate
gravity from motion in the road-frame specific force (§II-A, eq. 2):

.. math:: \sin\gamma = \frac{a_{xr} - \dot v_x}{g}, \quad
          \sin\beta = \frac{a_{yr} - v_x \omega_z}{g \cos\gamma}

with :math:`\dot v_x` from a filtered derivative of the speed and
:math:`\omega_z` the yaw rate (zero without rates). These are the slopes of
the road plane along and across the vehicle's heading: when the heading
swings across a banked road (the banked chicane's weave turns it by up to
19 deg), the slope under the car swings too (+-5.6 deg there), and the
lateral slip acceleration :math:`\dot v_y`, which is not measured, reaches
1.8 m/s^2. Both average out over a manoeuvre, so the bank is low-passed by
two first-order stages of 2.5 s and returns the road's own bank; the grade,
whose motion term :math:`\dot v_x` is measured, by one stage of 1 s (it
follows a change of grade within about 3 s). Both filters start at the first
sample's value.

The step is one CasADi Function (sequential scalar updates, Joseph form, a
skipped row for a missing input); ``run`` loops it in compiled C.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import step_flags, step_name
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import equilibrium_residual, suspension_loads
from wheelload.estimators.kernels.kalman import sequential_update
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.estimators.result import Estimate
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.body_attitude import attitude_function
from wheelload.models.family.road_angle import STATE_NAMES, BodyInertia, road_angle_model
from wheelload.models.input_validity import MAX_INTERVAL, interval_is_valid, sanitise

N = len(STATE_NAMES)
#: Measured states (eq. 16): roll, roll rate, pitch, pitch rate, 4 loads, 3 road-frame
#: accelerations.
MEASURED = (0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 12)


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


ANGLE_STATE = ("started", "speed", "speed_rate", "grade", "bank_stage", "bank")


def step_function(
    vehicle: Vehicle, tuning: RoadAngleTuning, model: SuspensionModel = DEFAULT_MODEL
) -> ca.Function:
    """The filter step: predict with the interval's ``F, Q``, sequential update, road angles."""
    x = ca.SX.sym("x", N)
    P = ca.SX.sym("P", N, N)
    angle = ca.SX.sym("angle_state", len(ANGLE_STATE))
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    F = ca.SX.sym("F", N, N)
    Q = ca.SX.sym("Q", N, N)
    p = ca.SX.sym("p", len(ModelParameters.names()))
    u = sanitise(u_raw, valid)
    d, acc, vx, rates = u[0:4], u[8:11], u[11], u[12:15]
    ok = interval_is_valid(dt)
    dt_safe = ca.if_else(ok, dt, 1.0)

    roll, pitch, acc_road = attitude_function(vehicle)(d, acc)
    loads_measured = suspension_loads(model, u, valid, p)
    z = ca.vertcat(roll, rates[0], pitch, rates[1], loads_measured, acc_road)
    travel_ok = valid[0] * valid[1] * valid[2] * valid[3]
    acc_ok = travel_ok * valid[8] * valid[9] * valid[10]
    wheel_ok = [valid[i] * valid[4 + i] for i in range(4)]
    mask = ca.vertcat(travel_ok, valid[12], travel_ok, valid[13], *wheel_ok, acc_ok, acc_ok, acc_ok)
    mask = mask * ok
    r = ca.vertcat(
        tuning.angle_std**2, tuning.rate_std**2, tuning.angle_std**2, tuning.rate_std**2,
        *[vehicle.filter.suspension_noise_density / dt_safe] * 4,
        *[tuning.acceleration_std**2] * 3,
    )  # fmt: skip
    H = np.zeros((len(MEASURED), N))
    H[np.arange(len(MEASURED)), MEASURED] = 1.0
    x_pred = ca.if_else(ok, ca.mtimes(F, x), x)
    P_pred = ca.if_else(ok, ca.mtimes([F, P, F.T]) + Q, P)
    x_new, P_new = sequential_update(x_pred, P_pred, z, ca.DM(H), r, mask)

    # Road grade and bank (module docstring): filtered speed derivative, eq. (2), low-passes.
    started, speed, speed_rate, grade, bank_stage, bank = (angle[i] for i in range(6))
    speed_ok = valid[11]
    blend_v = ca.exp(-dt_safe / tuning.speed_derivative_time_constant)
    rate_new = ca.if_else(
        speed_ok * started, blend_v * speed_rate + (1 - blend_v) * (vx - speed) / dt_safe,
        speed_rate,
    )  # fmt: skip
    speed_new = ca.if_else(speed_ok, vx, speed)
    yaw = rates[2] * valid[14]
    grade_now = ca.asin(ca.fmin(ca.fmax((x_new[8] - rate_new) / GRAVITY, -1), 1))
    lateral = (x_new[10] - speed_new * yaw) / (GRAVITY * ca.cos(grade_now))
    bank_now = ca.asin(ca.fmin(ca.fmax(lateral, -1), 1))
    blend_g = ca.exp(-dt_safe / tuning.grade_time_constant)
    blend_b = ca.exp(-dt_safe / tuning.bank_time_constant)
    stage_new = blend_b * bank_stage + (1 - blend_b) * bank_now
    angles_new = ca.if_else(
        started,
        ca.vertcat(
            1, speed_new, rate_new, blend_g * grade + (1 - blend_g) * grade_now, stage_new,
            blend_b * bank + (1 - blend_b) * stage_new,
        ),
        ca.vertcat(1, speed_new, rate_new, grade_now, bank_now, bank_now),
    )  # fmt: skip
    angles_new = ca.if_else(ok, angles_new, angle)

    loads = x_new[4:8]
    std = ca.sqrt(ca.fmax(ca.diag(P_new)[4:8], 0))
    residual, eq_ok = equilibrium_residual(model, u, valid, p, loads)
    rejected = 1 - ok
    missing = ca.fmax(1 - eq_ok, rejected)
    flags = step_flags([ca.fmax(1 - wheel_ok[i], rejected) for i in range(4)], missing, rejected)
    return ca.Function(
        step_name("wheelload_road_angle_step", model),
        [x, P, angle, u_raw, valid, dt, F, Q, p],
        [x_new, P_new, angles_new, loads, std, residual, flags],
        ["x", "P", "angle_state", "u", "u_valid", "dt", "F", "Q", "p"],
        ["x_next", "P_next", "angle_state_next", "loads", "std", "residual", "flags"],
    )


class RoadAngleKF(FamilyMethod):
    """14-state road-angle KF; loads with standard deviations, and road grade and bank.

    The step is one CasADi Function; ``run`` loops it in compiled C, with the
    interval's transition and process noise (matrix exponential, Van Loan)
    computed once per distinct interval and fed in per sample.
    """

    name = "road-angle KF"
    has_std = True
    interval_names = ("F", "Q")

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        inertia: BodyInertia | None = None,
        tuning: RoadAngleTuning = RoadAngleTuning(),
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        # the vehicle file's body inertia unless given
        self.inertia = BodyInertia.from_vehicle(vehicle) if inertia is None else inertia
        self.tuning = tuning
        model = road_angle_model(vehicle, self.inertia)
        x = ca.SX.sym("x", N)
        self.A = np.asarray(ca.DM(ca.jacobian(model(x)[0], x)), float)
        self._noise = np.zeros(N)  # process noise densities per state
        self._noise[[1, 3]] = tuning.angle_acceleration_density
        self._noise[4:8] = vehicle.filter.process_noise_density
        self._noise[[9, 11, 13]] = tuning.jerk_density
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return step_function(self.vehicle, self.tuning, self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        """``x`` at rest on the static loads, its ``P``, and the road-angle filters' state."""
        x0 = np.zeros(N)
        x0[4:8] = self.parameters.static()
        x0[12] = GRAVITY
        std = np.zeros(N)
        std[[0, 2]], std[[1, 3]] = 0.02, 0.1
        std[4:8] = self.vehicle.filter.initial_std
        std[[8, 10, 12]], std[[9, 11, 13]] = 2.0, 5.0
        return (x0, np.diag(std**2), np.zeros(len(ANGLE_STATE)))

    def fixed_arrays(self) -> tuple[np.ndarray, ...]:
        return (self.parameters.vector(),)

    @functools.lru_cache(maxsize=64)  # noqa: B019  (one model per sample interval)
    def _discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """``(F, Q)`` over ``dt``: exact transition, Van Loan process noise."""
        if not (np.isfinite(dt) and 0.0 < dt < MAX_INTERVAL):
            return np.eye(N), np.zeros((N, N))
        M = np.zeros((2 * N, 2 * N))
        M[:N, :N] = -self.A * dt
        M[:N, N:] = np.diag(self._noise) * dt
        M[N:, N:] = self.A.T * dt
        import scipy.linalg  # imported where used: listing the methods stays fast

        E = scipy.linalg.expm(M)
        F = E[N:, N:].T
        Q = F @ E[:N, N:]
        return F, 0.5 * (Q + Q.T)

    def interval_inputs(self, dt: np.ndarray) -> list[np.ndarray]:
        """``F`` and ``Q`` of each interval (rounded to 0.1 us), column-major rows (n, 196)."""
        keys = np.round(np.asarray(dt, float), 7)
        unique, index = np.unique(keys, return_inverse=True)
        pairs = [self._discrete(float(k)) for k in unique]
        F = np.array([f.ravel(order="F") for f, _ in pairs])[index]
        Q = np.array([q.ravel(order="F") for _, q in pairs])[index]
        return [F, Q]

    def run_with_road_angles(self, signals: Signals) -> tuple[Estimate, np.ndarray]:
        """The estimate and the road grade and bank [rad] of every sample, shape (n, 2)."""
        history, (loads, std, residual, flags) = self.run_loop(signals, record=(2,))
        estimate = Estimate(
            t=signals.t.copy(),
            loads=loads,
            std=std,
            residual=residual,
            flags=np.rint(flags[:, 0]).astype(np.int64),
        )
        return estimate, history[2][:, [3, 5]]


@dataclass(frozen=True, kw_only=True)
class RoadAngleOptions:
    """Options of the road-angle KF (``build("road-angle", vehicle, **options)``)."""

    inertia: BodyInertia | None = None  # body roll/pitch inertia; None: the vehicle file's
    tuning: RoadAngleTuning = RoadAngleTuning()  # noise densities and time constants


INFO = MethodInfo(
    name="road-angle",
    description="14-state KF with roll/pitch dynamics and road-frame accelerations; grade, bank",
    reference="Jiang et al., road-angle paper §II-III, eq. 4-18",
    build=RoadAngleKF,
    options=RoadAngleOptions,
    model_choice=True,
)
