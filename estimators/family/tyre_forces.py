r"""Tyre forces per wheel: the corner-based paper's observers on the two-stage KF's loads.

- ``tyre-pid`` (§III-A, eq. 4-9): :math:`F_x` of each wheel from its spin and torque, the
  PI spin observer of :func:`~wheelload.models.family.tyre_forces.observer_matrices`
  (the printed eq. 4-5 need the unknown :math:`F_x`; the implementable form has eq. 9's
  error dynamics), discretised exactly with the torque and spin held over the interval
  (Remark 1), minus the rolling resistance on the KF's :math:`F_z`.
- ``tyre-lateral`` (§III-B, eq. 10-16): a Kalman filter on
  :math:`(F_{yf}, F_{yr}, e, r)`: the axles' lateral forces, the front left/right
  difference beyond the load split (the paper's :math:`\bar F_{yf}`; see
  :func:`~wheelload.models.family.tyre_forces.body_force_rows`) and the yaw rate; measured
  the tyres' force sums from the accelerometer (road frame, drag, IMU lever arm) and the
  gyro's yaw rate. Random-walk forces (:math:`A_y = 0`, eq. 10), the yaw rate integrated
  from eq. 3. Covariance switching (§IV): where any wheel's spin acceleration reaches
  ``slip_threshold`` the filter takes the paper's high-slip pair, :math:`Q` times
  :math:`(0.036/0.11)^2` and :math:`R` times :math:`(0.4/0.018)^2` (the paper's ratios).
- ``tyre-forces``: the KF's :math:`F_z` with σ, ``tyre-pid``'s :math:`F_x` and
  ``tyre-lateral``'s :math:`F_y`, each with σ.
- ``tyre-rigid``: the baseline, the same force sums :math:`S_x, S_y` split to the wheels by
  the KF's normal-load share (both directions; no drive layout is assumed).

All four run the registered two-stage KF for :math:`F_z` and need the log's ``omega_*``,
``torque_*`` and ``steer`` (rigid: none of them); a missing one is a one-line error. The
wheel's spin inertia and rolling-resistance coefficient come from the vehicle file's
``[plant]`` section, the only place the file holds them. σ of :math:`F_x`: the
spin noise through the observer (its impulse response's energy) and 30 % of the rolling
resistance; of :math:`F_y`: the filter's covariance mapped to the wheels.
"""

from __future__ import annotations

import enum
import functools
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.discretise import expm
from wheelload.estimators.kf.method import build_kf
from wheelload.estimators.logs.signals import Signals
from wheelload.estimators.protocol import MethodInfo, Sample
from wheelload.estimators.result import Estimate
from wheelload.models import ModelParameters, Vehicle
from wheelload.models.aero import aero_forces
from wheelload.models.body_attitude import attitude_function
from wheelload.models.family.tyre_forces import (
    body_force_rows,
    cornering_split_exponent,
    load_share_split,
    observer_gains,
    observer_matrices,
    rolling_resistance_force,
    split_weights,
    wheel_lateral_forces,
)
from wheelload.models.plant.dynamics import corners, vehicle_plant

#: The paper's nominal and high-slip covariances (§IV): Q 0.11^2 -> 0.036^2, R 0.018^2 -> 0.4^2.
HIGH_SLIP_Q = (0.036 / 0.11) ** 2
HIGH_SLIP_R = (0.4 / 0.018) ** 2


class LateralSplit(enum.Enum):
    """How an axle's lateral force splits left/right before the filter's :math:`e`."""

    LOAD = "load"  # F_z share: the paper's simple alternative (§III-B)
    CORNERING_STIFFNESS = "cornering-stiffness"  # F_z^gamma, the tyres' load sensitivity


class TyreInputError(ValueError):
    """A log without a channel the tyre-force estimators need."""


@dataclass(frozen=True, kw_only=True)
class TyreSettings:
    """Observer and filter settings (SI units)."""

    observer_frequency: float = 3.0  # Hz, natural frequency of eq. 9's poles
    observer_damping: float = 0.8  # -
    spin_noise: float = 0.02  # rad/s, 1 sigma white spin noise (sigma of F_x)
    rolling_resistance_std: float = 0.3  # share of the rolling resistance (sigma of F_x)
    force_rate: float = 4000.0  # N/sqrt(s), random walk of the axle lateral forces
    split_rate: float = 1.0  # N/sqrt(s), random walk of e
    yaw_rate_noise: float = 0.01  # rad/s^2/sqrt(Hz)... process noise of r per sqrt(s)
    force_noise: float = 120.0  # N, 1 sigma of the force sums S_x, S_y (model error)
    gyro_noise: float = 0.002  # rad/s, 1 sigma of the yaw rate
    initial_force_std: float = 500.0  # N
    slip_threshold: float = 40.0  # rad/s^2, |d omega / dt| of any wheel: high slip
    split: LateralSplit = LateralSplit.CORNERING_STIFFNESS

    def __post_init__(self) -> None:
        for key in ("observer_frequency", "observer_damping", "force_rate", "split_rate",
                    "yaw_rate_noise", "force_noise", "gyro_noise", "initial_force_std",
                    "slip_threshold"):  # fmt: skip
            if not getattr(self, key) > 0:
                raise ValueError(f"tyre settings: {key} must be > 0, got {getattr(self, key)}")


@dataclass(frozen=True, kw_only=True)
class TyreState:
    """The KF's state, the spin observers (4, 2), the lateral filter and the last spins."""

    kf: object
    # (4, 4): omega_hat, xi, last torque, last spin; None until a sample with both
    observer: np.ndarray | None = None
    x: np.ndarray | None = None  # (4,) F_yf, F_yr, e, r
    P: np.ndarray | None = None  # (4, 4)
    spin: np.ndarray | None = None  # (4,) last spins, for the slip detection
    fx: np.ndarray | None = None  # (4,) last F_x, held through a missing sample


@dataclass(frozen=True, kw_only=True)
class Constants:
    """Numbers of the vehicle the observers need (module docstring)."""

    inertia: np.ndarray  # (4,) spin inertia [kg m^2]
    radius: np.ndarray  # (4,) static loaded radius [m]
    rolling: float  # rolling-resistance coefficient
    mass: float  # whole-vehicle mass [kg]
    yaw_inertia: float  # about the sprung CG, unsprung masses included [kg m^2]
    lf: float
    lr: float
    track_front: float
    track_rear: float
    imu_x: float  # IMU ahead of the sprung CG [m]
    split_exponents: np.ndarray  # (2,) front, rear: gamma of the split (LateralSplit)


def vehicle_constants(vehicle: Vehicle, split: LateralSplit) -> Constants:
    """:class:`Constants` of ``vehicle`` (its ``[plant]`` section for the wheels and tyres;
    the split's exponent at each axle's static load)."""
    items = corners(vehicle)
    g = vehicle.geometry
    tyre = vehicle_plant(vehicle).tyre
    exponents = [
        1.0
        if split is LateralSplit.LOAD
        else cornering_split_exponent(c.static_load, c.nominal_load, tyre.cornering_load_y)
        for c in (items[0], items[2])
    ]
    return Constants(
        inertia=np.array([c.spin_inertia for c in items]),
        radius=np.array([c.radius - c.static_load / c.tyre_rate for c in items]),
        rolling=float(vehicle_plant(vehicle).tyre.rolling_resistance),
        mass=float(vehicle.mass.total),
        yaw_inertia=float(vehicle.mass.inertia[2])
        + sum(c.unsprung * (c.x**2 + c.y**2) for c in items),
        lf=float(g.lf),
        lr=float(g.lr),
        track_front=float(g.track_front),
        track_rear=float(g.track_rear),
        imu_x=float(g.imu_position[0]),
        split_exponents=np.array(exponents),
    )


@functools.cache
def discrete_observer(inertia: float, radius: float, frequency: float, damping: float, dt: float):
    r"""``(Phi, Gamma1, Gamma2, C, D, noise gain)`` of one wheel's observer over ``dt``.

    First-order hold (torque and spin linear between samples, Franklin, Powell & Workman
    §6.3.2): :math:`z_{k+1} = \Phi z_k + \Gamma_1 u_k + \Gamma_2 (u_{k+1} - u_k)`, exact for
    a spin ramp (a constant force), where a zero-order hold would lag the spin by half a
    sample and bias :math:`\hat F` by about :math:`J \dot\omega / (2 R)`. The noise gain is
    the root energy of the spin-to-force impulse response (σ of :math:`F_x`).
    """
    k1, k2 = observer_gains(inertia=inertia, radius=radius, frequency=frequency, damping=damping)
    a, b, c, d = observer_matrices(inertia=inertia, radius=radius, k1=k1, k2=k2)
    block = np.zeros((6, 6))
    block[:2, :2], block[:2, 2:4], block[2:4, 4:] = a * dt, b * dt, np.eye(2)
    exact = np.array(expm(ca.DM(block)))
    phi, gamma1, gamma2 = exact[:2, :2], exact[:2, 2:4], exact[:2, 4:]
    # Response of F = C z + D u to a unit spin impulse (u_0 = (0, 1), then 0).
    z, previous, response = np.zeros(2), np.zeros(2), []
    for k in range(int(20.0 / (frequency * dt)) + 10):
        u = np.array([0.0, 1.0 if k == 0 else 0.0])
        z = z if k == 0 else phi @ z + gamma1 @ previous + gamma2 @ (u - previous)
        response.append(c @ z + d @ u)
        previous = u
    return phi, gamma1, gamma2, c, d, float(np.sqrt(np.sum(np.square(response))))


class TyreForces:
    """Tyre forces per wheel on the KF's loads (module docstring); ``outputs`` picks which."""

    name = "tyre-forces"
    has_std = True

    def __init__(
        self,
        vehicle: Vehicle,
        settings: TyreSettings = TyreSettings(),
        *,
        longitudinal: bool = True,
        lateral: bool = True,
    ) -> None:
        self.vehicle = vehicle
        self.settings = settings
        self.longitudinal = longitudinal or lateral  # the lateral filter needs F_x
        self.show_fx = longitudinal
        self.lateral = lateral
        self.constants = vehicle_constants(vehicle, settings.split)
        self.kf = build_kf(vehicle)
        self._attitude = attitude_function(vehicle)
        self._parameters = ModelParameters.from_vehicle(vehicle)

    def initial_state(self) -> TyreState:
        return TyreState(kf=self.kf.initial_state())

    # -- the pieces of one sample -------------------------------------------------------

    def force_sums(self, sample: Sample) -> np.ndarray:
        r"""``(S_x, S_y)``: the tyre force sums from the specific force (module docstring),
        the centripetal lever-arm term :math:`r^2 x_{imu}` removed from :math:`a_x`."""
        k = self.constants
        _, _, road = self._attitude(np.nan_to_num(sample.d), sample.acc)
        road = np.asarray(road).ravel()
        rate = 0.0 if sample.rates is None else float(np.nan_to_num(sample.rates[2]))
        _, drag = aero_forces(sample.vx, self._parameters)
        return np.array([k.mass * (road[0] + rate**2 * k.imu_x) + drag, k.mass * road[1]])

    def _fx(self, state: TyreState, sample: Sample, loads: np.ndarray, dt: float):
        """The spin observers' step: ``(observer, fx, fx_std)``."""
        s, k = self.settings, self.constants
        spin, torque = sample.spin, sample.torque
        ok = spin is not None and torque is not None and np.all(np.isfinite(spin))
        ok = ok and np.all(np.isfinite(torque))
        if not ok:
            held = np.zeros(4) if state.fx is None else state.fx
            return state.observer, held, np.full(4, 1e4)
        observer = np.empty((4, 4)) if state.observer is None else state.observer.copy()
        fx, std = np.empty(4), np.empty(4)
        for i in range(4):
            phi, gamma1, gamma2, c, d, gain = discrete_observer(
                k.inertia[i], k.radius[i], s.observer_frequency, s.observer_damping,
                round(float(dt), 9))  # fmt: skip
            u = np.array([torque[i], spin[i]])
            if state.observer is None:  # start in equilibrium: F = -k2 xi = T / R, no error
                z = np.array([spin[i], (torque[i] / k.radius[i]) / c[1]])
            else:
                z, previous = observer[i, :2], observer[i, 2:]
                z = phi @ z + gamma1 @ previous + gamma2 @ (u - previous)
            observer[i] = [*z, *u]
            rolling = rolling_resistance_force(loads[i], spin[i], k.rolling)
            fx[i] = c @ z + d @ u - rolling
            std[i] = np.hypot(gain * s.spin_noise, s.rolling_resistance_std * rolling)
        return observer, fx, std

    def _fy(self, state: TyreState, sample: Sample, loads: np.ndarray, fx: np.ndarray, dt):
        """The lateral filter's step: ``(x, P, fy, fy_std)``."""
        s, k = self.settings, self.constants
        steer = 0.0 if sample.steer is None or not np.isfinite(sample.steer) else sample.steer
        weights = split_weights(loads, k.split_exponents)
        share = (weights[1] - weights[0]) / (weights[0] + weights[1])
        h, offset = body_force_rows(steer, fx, lf=k.lf, lr=k.lr, track_front=k.track_front,
                                    track_rear=k.track_rear, share_front=share,
                                    inertia_z=k.yaw_inertia)  # fmt: skip
        x, P = state.x, state.P
        if x is None:
            rate = 0.0 if sample.rates is None else float(np.nan_to_num(sample.rates[2]))
            x = np.array([0.0, 0.0, 0.0, rate])
            P = np.diag([s.initial_force_std**2] * 3 + [s.gyro_noise**2])
        high_slip = False
        if state.spin is not None and sample.spin is not None and dt > 0:
            rate_of_spin = np.abs(np.asarray(sample.spin) - state.spin) / dt
            high_slip = bool(np.any(np.nan_to_num(rate_of_spin) >= s.slip_threshold))
        q_scale = HIGH_SLIP_Q if high_slip else 1.0
        r_scale = HIGH_SLIP_R if high_slip else 1.0
        # Predict: forces random walk, r integrated from eq. 3's yaw acceleration.
        F = np.eye(4)
        F[3, :3] = dt * h[2]
        x = F @ x + np.array([0.0, 0.0, 0.0, dt * offset[2]])
        Q = q_scale * dt * np.diag([s.force_rate**2, s.force_rate**2, s.split_rate**2,
                                    s.yaw_rate_noise**2])  # fmt: skip
        P = F @ P @ F.T + Q
        # Update: S_x, S_y at the IMU (lever arm: m x_imu r_dot), and the gyro's r.
        sums = self.force_sums(sample)
        H = np.zeros((3, 4))
        H[0, :3] = h[0]
        H[1, :3] = h[1] + k.mass * k.imu_x * h[2]
        H[2, 3] = 1.0
        z = np.array([sums[0] - offset[0], sums[1] - offset[1] - k.mass * k.imu_x * offset[2],
                      np.nan if sample.rates is None else sample.rates[2]])  # fmt: skip
        R = r_scale * np.diag([s.force_noise**2, s.force_noise**2, s.gyro_noise**2])
        valid = np.isfinite(z)
        if valid.any():
            Hv, Rv = H[valid], R[np.ix_(valid, valid)]
            S = Hv @ P @ Hv.T + Rv
            K = np.linalg.solve(S, Hv @ P).T
            x = x + K @ (z[valid] - Hv @ x)
            I_KH = np.eye(4) - K @ Hv
            P = I_KH @ P @ I_KH.T + K @ Rv @ K.T
            P = 0.5 * (P + P.T)
        fy, G = wheel_lateral_forces(x[:3], weights)
        std = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", G, P[:3, :3], G), 0.0))
        return x, P, fy, std

    # -- the protocol -----------------------------------------------------------------

    def step(self, state: TyreState, sample: Sample, dt: float) -> tuple[TyreState, Estimate]:
        kf_state, loads_estimate = self.kf.step(state.kf, sample, dt)
        loads = loads_estimate.loads[0]
        observer, fx, fx_std = self._fx(state, sample, loads, dt)
        new = replace(state, kf=kf_state, observer=observer, fx=fx)
        fy = fy_std = None
        if self.lateral:
            x, P, fy, fy_std = self._fy(state, sample, loads, fx, dt)
            new = replace(new, x=x, P=P)
        new = replace(new, spin=None if sample.spin is None else np.asarray(sample.spin, float))
        row = lambda a: None if a is None else np.asarray(a, float).reshape(1, 4)  # noqa: E731
        estimate = replace(
            loads_estimate,
            fx=row(fx) if self.show_fx else None,
            fx_std=row(fx_std) if self.show_fx else None,
            fy=row(fy),
            fy_std=row(fy_std),
        )
        return new, estimate

    def run(self, signals: Signals) -> Estimate:
        """The whole log: the KF's ``run`` for the loads, then the observers sample by sample
        (the same numbers as :meth:`step`)."""
        require_wheel_channels(signals)
        from wheelload.estimators.samples import samples

        loads = self.kf.run(signals)
        state = self.initial_state()
        dts = np.concatenate([np.diff(signals.t)[:1], np.diff(signals.t)])
        n = len(signals)
        fx, fx_std, fy, fy_std = (np.zeros((n, 4)) for _ in range(4))
        for j, (sample, dt) in enumerate(zip(samples(signals), dts)):
            observer, fx[j], fx_std[j] = self._fx(state, sample, loads.loads[j], float(dt))
            state = replace(state, observer=observer, fx=fx[j])
            if self.lateral:
                x, P, fy[j], fy_std[j] = self._fy(state, sample, loads.loads[j], fx[j], float(dt))
                state = replace(state, x=x, P=P)
            state = replace(state, spin=np.asarray(sample.spin, float))
        return replace(
            loads,
            fx=fx if self.show_fx else None,
            fx_std=fx_std if self.show_fx else None,
            fy=fy if self.lateral else None,
            fy_std=fy_std if self.lateral else None,
        )


def require_wheel_channels(signals: Signals) -> None:
    """A one-line error naming the first tyre-force channel the log lacks."""
    for name, values in (("omega_fl", signals.spin), ("torque_fl", signals.torque),
                         ("steer", signals.steer)):  # fmt: skip
        if values is None:
            raise TyreInputError(
                f"{signals.source}: no column '{name}': the tyre-force estimators need "
                "omega_fl..omega_rr [rad/s], torque_fl..torque_rr [N m] and steer [rad]"
            )


class RigidSplit(TyreForces):
    """Baseline: the force sums split by the KF's normal-load share (no wheel channels)."""

    name = "tyre-rigid"
    has_std = False

    def step(self, state: TyreState, sample: Sample, dt: float) -> tuple[TyreState, Estimate]:
        kf_state, loads_estimate = self.kf.step(state.kf, sample, dt)
        fx, fy = self._split(sample, loads_estimate.loads)
        return replace(state, kf=kf_state), replace(loads_estimate, fx=fx, fy=fy)

    def _split(self, sample: Sample, loads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        sums = self.force_sums(sample)
        return load_share_split(sums[:1], loads), load_share_split(sums[1:], loads)

    def run(self, signals: Signals) -> Estimate:
        from wheelload.estimators.samples import samples

        loads = self.kf.run(signals)
        parts = [self._split(sample, loads.loads[j : j + 1])
                 for j, sample in enumerate(samples(signals))]  # fmt: skip
        return replace(
            loads,
            fx=np.concatenate([p[0] for p in parts]),
            fy=np.concatenate([p[1] for p in parts]),
        )


def _pid(vehicle: Vehicle, settings: TyreSettings = TyreSettings()) -> TyreForces:
    method = TyreForces(vehicle, settings, lateral=False)
    method.name = "tyre-pid"
    return method


def _lateral(vehicle: Vehicle, settings: TyreSettings = TyreSettings()) -> TyreForces:
    method = TyreForces(vehicle, settings, longitudinal=False)
    method.name = "tyre-lateral"
    return method


INFO = (
    MethodInfo(
        name="tyre-pid",
        description="F_x per wheel: PI spin observer on the wheel dynamics, KF loads",
        reference="corner-based paper §III-A, eq. 1, 4-9",
        build=_pid,
    ),
    MethodInfo(
        name="tyre-lateral",
        description="F_y per wheel: adaptive KF on axle forces and yaw rate, KF loads",
        reference="corner-based paper §III-B, eq. 2-3, 10-16, §IV covariance switching",
        build=_lateral,
    ),
    MethodInfo(
        name="tyre-forces",
        description="F_x, F_y, F_z per wheel with sigma: KF loads + tyre-pid + tyre-lateral",
        reference="corner-based paper §III; road-angle paper §III (vertical block feeds "
        "the lateral block)",
        build=TyreForces,
    ),
    MethodInfo(
        name="tyre-rigid",
        description="baseline: m a_x, m a_y (road frame, drag) split by the KF's load share",
        reference="rigid-body baseline (corner-based paper eq. 2, load-share split)",
        build=RigidSplit,
    ),
)
