r"""Tyre forces per wheel: the corner-based paper's observers on the two-stage KF's loads.

- ``tyre-pid`` (§III-A, eq. 4-9): :math:`F_x` of each wheel from its spin and torque, the
  spin observer of :func:`~wheelload.models.family.tyre_forces.observer_matrices` in eq.
  4's form (the torque's feed-through :math:`T/R` and the :math:`k_3` term; the paper's
  gains map by their poles, :func:`~wheelload.models.family.tyre_forces.observer_gains`),
  discretised exactly with the torque and spin linear between samples (first-order hold;
  the paper's Remark 1 holds them, which lags a spin ramp by half a sample), minus the
  rolling resistance on the KF's :math:`F_z`. The torque's feed-through is scaled by a
  gain :math:`g` (1 nominal) that the lateral filter estimates from :math:`S_x`, so a
  torque signal a few % off is learned, its σ in :math:`F_x`'s. In high slip and
  ``slip_hold`` after it, :math:`F_x` is a second, fast observer's (30 Hz against the
  nominal 1 Hz, both always running): a cycling ABS moves the force at 4-10 Hz, which the
  nominal one cannot follow (F_x 46 → 26 % of its RMS on the plant's ABS braking), while
  elsewhere the fast one would pass the spin noise (lane change 3.5 → 25 %).
- ``tyre-lateral`` (§III-B, eq. 10-16): a Kalman filter on
  :math:`(F_{yf}, F_{yr}, e, r, g, b_x)`: the axles' lateral forces, the front left/right
  difference beyond the load split (the paper's :math:`\bar F_{yf}`; see
  :func:`~wheelload.models.family.tyre_forces.body_force_rows`) and the yaw rate; measured
  the tyres' force sums from the accelerometer (road frame, drag, IMU lever arm) and the
  gyro's yaw rate; :math:`g` and :math:`b_x` (the bias of :math:`S_x`: the
  accelerometer's, the drag's) enter the :math:`S_x` row. Random-walk forces
  (:math:`A_y = 0`, eq. 10), the yaw rate integrated from eq. 3. High slip (§IV): the
  paper's :math:`|\dot\omega_{ij}| \ge \dot\omega_{th}` taken per unit speed, on the
  wheel's slip ratio :math:`\kappa = (R_e\omega - v)/v`
  (:func:`~wheelload.models.family.tyre_forces.slip_ratios`, :math:`R_e` the effective
  rolling radius under the KF's :math:`F_z`): :math:`|\dot\kappa| \ge \dot\kappa_{th}`
  (low-passed over ``slip_time``). From :math:`R\dot\omega = \dot v (1 + \kappa) + v
  \dot\kappa`, the car's own deceleration drops out, and per unit speed a stable wheel's
  slip, which follows its torque (:math:`\kappa \approx F_x / C_\kappa`), is not flagged at
  50 m/s where :math:`v\dot\kappa` is large: a wheel past its force peak runs away at any
  speed. :math:`\dot\kappa_{th}` = 1/s, a choice: the paper's 40 rad/s² on a 0.33 m wheel
  at 13 m/s (47 km/h), and on the plant it parts a cycling ABS from a lap (results.md). It
  sets ``StepFlag.HIGH_SLIP``; with ``switch_covariances`` the filter also takes the
  paper's high-slip pair, :math:`Q` times :math:`(0.036/0.11)^2` and :math:`R` times
  :math:`(0.4/0.018)^2` (the paper's ratios). Off by default: on the plant's laps and kerb
  it raised the F_y error wherever it acted (the force sums it mutes stay valid in slip).
- ``tyre-forces``: the KF's :math:`F_z` with σ, ``tyre-pid``'s :math:`F_x` and
  ``tyre-lateral``'s :math:`F_y`, each with σ.
- ``tyre-rigid``: the baseline, the same force sums :math:`S_x, S_y` split to the wheels by
  the KF's normal-load share (both directions; no drive layout is assumed).

The paper splits nothing left/right beyond its state :math:`\bar F_{yf}` (front) and the
normal-load share it names as the simple alternative; ours splits each axle by the tyres'
load sensitivity (:class:`~wheelload.estimators.family.tyres.step.LateralSplit`;
``LOAD`` is the paper's share), and the front
difference beyond it (:math:`e`) has a tight prior: it is seen only through
:math:`\sin\delta` in the yaw row, where any yaw-model error would land on it.

All four run the registered two-stage KF for :math:`F_z` and need the log's ``omega_*``,
``torque_*`` and ``steer`` (rigid: none of them); a missing one is a one-line error. The
wheels' spin inertia and rolling-resistance coefficient come from the vehicle file's
``[wheels]`` section (required), the tyre coefficients of the left/right split
(:func:`~wheelload.models.family.tyre_forces.tyre_split`) from its optional
``[cornering]`` section (beyond the paper, which assumes no tyre model; without it the
split is the paper's normal-load share); no estimator reads ``[plant]``. The force sums
and the yaw row take the KF's online mass properties (its payload estimate). σ of
:math:`F_x`: the spin noise through the observer (its impulse response's energy), 30 % of
the rolling resistance and 4 % of the force (loaded radius, torque); of :math:`F_y`: the
filter's covariance mapped to the wheels.

The observers are one CasADi step (:mod:`~wheelload.estimators.family.tyres.step`), called
by :meth:`TyreForces.step` and looped in compiled C by :meth:`TyreForces.run`;
``wheelload codegen --tyre-forces`` emits the same step as C
(:mod:`~wheelload.estimators.codegen.tyre`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from wheelload.estimators.family.tyres.step import (
    CORE,
    CORE_INPUTS,
    LateralSplit,
    observer_inputs,
    tyre_core_function,
)
from wheelload.estimators.kernels.discretise import expm
from wheelload.estimators.kf.method import build_kf
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.protocol import MethodInfo
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.types import Sample, Signals
from wheelload.models import ModelParameters, Vehicle
from wheelload.models.aero import aero_forces
from wheelload.models.body_attitude import attitude_function
from wheelload.models.family.tyre_forces import (
    load_share_split,
    observer_gains,
    observer_matrices,
)
from wheelload.models.mass_properties import static_loads
from wheelload.models.vehicle.wheel_geometry import loaded_radii, wheel_centres

#: The paper's nominal and high-slip covariances (§IV): Q 0.11^2 -> 0.036^2, R 0.018^2 -> 0.4^2.
HIGH_SLIP_Q = (0.036 / 0.11) ** 2
HIGH_SLIP_R = (0.4 / 0.018) ** 2


class TyreInputError(ValueError):
    """A log without a channel the tyre-force estimators need."""


@dataclass(frozen=True, kw_only=True)
class TyreSettings:
    """Observer and filter settings (SI units)."""

    observer_frequency: float = 1.0  # Hz, natural frequency of eq. 9's poles
    observer_damping: float = 0.8  # -
    # In high slip and slip_hold after it F_x takes a fast observer's: a cycling ABS
    # moves the force at 4-10 Hz (module docstring).
    slip_observer_frequency: float = 30.0  # Hz
    slip_hold: float = 0.2  # s
    spin_noise: float = 0.02  # rad/s, 1 sigma white spin noise (sigma of F_x)
    rolling_resistance_std: float = 0.3  # share of the rolling resistance (sigma of F_x)
    force_share_std: float = 0.04  # share of F_x: the loaded radius and torque (sigma of F_x)
    force_rate: float = 4000.0  # N/sqrt(s), random walk of the axle lateral forces
    # e, the front difference beyond the split, is seen only through sin(steer) in the yaw
    # row, where any yaw-model error lands on it: a tight prior and a slow walk keep it
    # near the split (the paper's simple alternative) unless the yaw row insists.
    split_std: float = 50.0  # N, initial sigma of e
    split_rate: float = 1.0  # N/sqrt(s), random walk of e
    yaw_rate_noise: float = 0.01  # rad/s^2/sqrt(Hz)... process noise of r per sqrt(s)
    force_noise: float = 120.0  # N, 1 sigma of the force sums S_x, S_y (model error)
    gyro_noise: float = 0.002  # rad/s, 1 sigma of the yaw rate
    initial_force_std: float = 500.0  # N
    torque_gain_std: float = 0.1  # -, initial sigma of the torque gain g (1 nominal)
    torque_gain_rate: float = 0.001  # 1/sqrt(s), random walk of g
    # S_x's bias: an MTi-class a_x turn-on bias (0.1 m/s^2) times m, and the drag's error.
    force_bias_std: float = 200.0  # N, initial sigma
    force_bias_rate: float = 5.0  # N/sqrt(s), random walk
    # High slip: |d kappa/dt| of any wheel's slip ratio, low-passed, at least this (a
    # choice: the paper's 40 rad/s^2 on a 0.33 m wheel at 13 m/s; module docstring).
    slip_ratio_rate: float = 1.0  # 1/s
    slip_time: float = 0.05  # s, time constant of that low-pass
    slip_speed: float = 2.0  # m/s, the slip ratio is taken per at least this speed
    switch_covariances: bool = False  # in high slip, the paper's Q and R (module docstring)
    # None: the tyres' load sensitivity where the file has [cornering], else the paper's
    # normal-load share.
    split: LateralSplit | None = None
    missing_std: float = 1.0e4  # N, sigma of an F_x held through a missing spin or torque

    def __post_init__(self) -> None:
        if not self.slip_hold >= 0:
            raise ValueError(f"tyre settings: slip_hold must be >= 0, got {self.slip_hold}")
        for key in ("observer_frequency", "slip_observer_frequency", "observer_damping",
                    "force_rate", "split_rate", "split_std", "yaw_rate_noise", "force_noise",
                    "gyro_noise",
                    "initial_force_std", "torque_gain_std", "torque_gain_rate",
                    "force_bias_std", "force_bias_rate", "slip_ratio_rate",
                    "slip_time", "slip_speed"):  # fmt: skip
            if not getattr(self, key) > 0:
                raise ValueError(f"tyre settings: {key} must be > 0, got {getattr(self, key)}")


@dataclass(frozen=True, kw_only=True)
class TyreState:
    """The KF's state and the observers' ``core`` (see :meth:`TyreForces.core_step`)."""

    kf: object
    core: np.ndarray  # the observers' state (tyre_step.CORE)


@dataclass(frozen=True, kw_only=True)
class Constants:
    """Numbers of the vehicle the observers need (module docstring)."""

    inertia: np.ndarray  # (4,) spin inertia [kg m^2]
    radius: np.ndarray  # (4,) static loaded radius [m]
    free_radius: np.ndarray  # (4,) unloaded tyre radius [m]
    vertical_stiffness: np.ndarray  # (4,) tyre vertical stiffness [N/m]
    rolling: float  # rolling-resistance coefficient
    mass: float  # whole-vehicle mass [kg]
    yaw_inertia: float  # about the sprung CG, unsprung masses included [kg m^2]
    lf: float
    lr: float
    track_front: float
    track_rear: float
    positions: tuple[tuple[float, float], ...]  # wheel centres (x, y) from the CG [m]
    imu_x: float  # IMU ahead of the sprung CG [m]
    cg_y: float  # the file's lateral CG [m] (the KF's mass properties' origin)
    nominal_loads: tuple[float, float]  # F_z0 front, rear [N] (the split's, if any)
    friction: float  # mu_y0
    load_sensitivity: float  # p_D2
    cornering_load: float  # p_Ky2


def vehicle_constants(vehicle: Vehicle) -> Constants:
    """:class:`Constants` of ``vehicle``: its ``[wheels]`` section (required), its
    ``[cornering]`` section where it has one, and the rest of the description."""
    if vehicle.wheels is None:
        raise TyreInputError(
            f"vehicle '{vehicle.name}' has no [wheels] section: the tyre-force methods need "
            "spin_inertia_front, spin_inertia_rear [kg m^2] and rolling_resistance [-] "
            "(see 'wheelload vehicle --template')"
        )
    g, t, m, wheels = vehicle.geometry, vehicle.tyres, vehicle.mass, vehicle.wheels
    positions = wheel_centres(g)
    unsprung = (m.unsprung_front / 2,) * 2 + (m.unsprung_rear / 2,) * 2
    cornering = vehicle.cornering
    return Constants(
        inertia=np.array([wheels.spin_inertia_front] * 2 + [wheels.spin_inertia_rear] * 2),
        radius=np.array(loaded_radii(t, static_loads(vehicle))),
        free_radius=np.array([t.radius_front] * 2 + [t.radius_rear] * 2),
        vertical_stiffness=np.array(
            [t.vertical_stiffness_front] * 2 + [t.vertical_stiffness_rear] * 2
        ),  # fmt: skip
        rolling=float(wheels.rolling_resistance),
        mass=float(m.total),
        yaw_inertia=float(m.inertia[2])
        + sum(mu * (x**2 + y**2) for mu, (x, y) in zip(unsprung, positions)),
        lf=float(g.lf),
        lr=float(g.lr),
        track_front=float(g.track_front),
        track_rear=float(g.track_rear),
        positions=positions,
        imu_x=float(g.imu_position[0]),
        cg_y=float(ModelParameters.from_vehicle(vehicle).cg_y),
        nominal_loads=(0.0, 0.0)
        if cornering is None
        else (cornering.nominal_load_front, cornering.nominal_load_rear),
        friction=0.0 if cornering is None else cornering.friction,
        load_sensitivity=0.0 if cornering is None else cornering.friction_load_sensitivity,
        cornering_load=0.0 if cornering is None else cornering.cornering_load,
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


@dataclass(frozen=True, kw_only=True)
class Inputs:
    """One sample's inputs of the observers (NaN where missing)."""

    spin: np.ndarray  # (4,) rad/s
    torque: np.ndarray  # (4,) N m
    steer: float  # rad
    rate: float  # yaw rate [rad/s]
    speed: float  # v_x [m/s]
    sums: np.ndarray  # (2,) S_x, S_y [N] (:meth:`TyreForces.force_sums`)
    loads: np.ndarray  # (4,) the KF's F_z [N]
    mass_properties: np.ndarray  # (4,) the KF's [m', δx, y_c', h']


def _given(values, size: int) -> np.ndarray:
    return np.full(size, np.nan) if values is None else np.asarray(values, float)


class TyreForces:
    """Tyre forces per wheel on the KF's loads (module docstring)."""

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
        self.settings = replace(settings, split=lateral_split(vehicle, settings.split))
        self.show_fx = longitudinal
        self.lateral = lateral  # the lateral filter runs on the observer's F_x either way
        self.constants = vehicle_constants(vehicle)
        self.kf = build_kf(vehicle)
        self._attitude = attitude_function(vehicle)
        self._parameters = ModelParameters.from_vehicle(vehicle)

    def initial_state(self) -> TyreState:
        return TyreState(kf=self.kf.initial_state(), core=np.zeros(CORE.size))

    @functools.cached_property
    def force_sum_function(self) -> ca.Function:
        r"""``force_sums(d[4], acc[3], vx, rate, mass_properties[4]) -> sums[2]``:
        :math:`(S_x, S_y)`, the tyres' force sums from the specific force in the road frame
        (module docstring) times the loaded car's mass :math:`m'`, the drag added and the
        centripetal lever-arm term :math:`r^2 (x_{imu} - \delta x)` removed from
        :math:`a_x` (``mass_properties``: the KF's ``[m', δx, y_c', h']``)."""
        k = self.constants
        d, acc = ca.SX.sym("d", 4), ca.SX.sym("acc", 3)
        vx, rate = ca.SX.sym("vx"), ca.SX.sym("rate")
        loaded = ca.SX.sym("mass_properties", 4)
        _, _, road = self._attitude(d, acc)
        _, drag = aero_forces(vx, self._parameters)
        mass, lever = loaded[0], k.imu_x - loaded[1]
        sums = ca.vertcat(mass * (road[0] + rate**2 * lever) + drag, mass * road[1])
        return ca.Function("force_sums", [d, acc, vx, rate, loaded], [sums],
                           ["d", "acc", "vx", "rate", "mass_properties"], ["sums"])  # fmt: skip

    def file_mass_properties(self) -> np.ndarray:
        """``[m, 0, y_c, h]`` of the file: the loaded car where no payload is estimated."""
        return self.kf.state_mass_properties(self.kf.initial_state())

    def mass_properties_of(self, loads: Estimate) -> np.ndarray:
        """``(n, 4)`` mass properties of the KF's estimate, the file's where it has none."""
        if loads.mass_properties is None:
            return np.tile(self.file_mass_properties(), (loads.loads.shape[0], 1))
        return np.asarray(loads.mass_properties, float)

    def force_sums(self, d: np.ndarray, acc: np.ndarray, vx, rate, mass_properties) -> np.ndarray:
        """``(n, 2)`` :meth:`force_sum_function` of ``n`` samples (a missing travel or yaw
        rate taken as 0; a missing acceleration or speed gives NaN where it enters)."""
        n = d.shape[0]
        sums = self.force_sum_function.map(n)(
            np.nan_to_num(d).T, np.asarray(acc, float).T, np.asarray(vx, float)[None],
            np.nan_to_num(np.asarray(rate, float))[None],
            np.asarray(mass_properties, float).reshape(n, 4).T,
        )  # fmt: skip
        return np.asarray(sums).reshape(2, n).T

    @functools.cached_property
    def core_function(self) -> ca.Function:
        """The observers' step (:func:`.step.tyre_core_function`)."""
        return tyre_core_function(self.constants, self.settings, (HIGH_SLIP_Q, HIGH_SLIP_R))

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        return CompiledLoop(self.core_function, 1, CORE_INPUTS[1:])

    def observer_input(self, dt: float) -> np.ndarray:
        """The core step's ``observer`` input for an interval ``dt`` (rounded to 1 ns): the
        nominal observers, then the fast ones of high slip."""
        k, s = self.constants, self.settings
        return np.concatenate([
            observer_inputs([discrete_observer(k.inertia[i], k.radius[i], frequency,
                                               s.observer_damping, round(float(dt), 9))
                             for i in range(4)])
            for frequency in (s.observer_frequency, s.slip_observer_frequency)
        ])  # fmt: skip

    def core_step(self, core: np.ndarray, inputs: Inputs, dt: float):
        """One sample of the observers: ``(core, fx, fx_std, fy, fy_std)``."""
        arguments = _core_arguments(
            np.concatenate([inputs.spin, inputs.torque, [inputs.steer]])[None],
            np.asarray(inputs.sums, float)[None], np.array([inputs.rate]),
            np.array([inputs.speed]), np.asarray(inputs.loads, float)[None],
            np.asarray(inputs.mass_properties, float)[None],
        )  # fmt: skip
        out = self.core_function(core, *[a[0] for a in arguments], dt, self.observer_input(dt))
        core, fx, fx_std, fy, fy_std, high_slip = (np.asarray(o, float).ravel() for o in out)
        return core, fx, fx_std, fy, fy_std, high_slip

    # -- the protocol -----------------------------------------------------------------

    def _estimate(self, loads: Estimate, fx, fx_std, fy, fy_std, high_slip) -> Estimate:
        """The KF's ``loads`` with the forces and ``HIGH_SLIP`` where the switching acted."""
        slipping = np.asarray(high_slip, float).ravel() > 0.5
        return replace(
            loads,
            flags=loads.flags | np.where(slipping, int(StepFlag.HIGH_SLIP), 0),
            fx=fx if self.show_fx else None,
            fx_std=fx_std if self.show_fx else None,
            fy=fy if self.lateral else None,
            fy_std=fy_std if self.lateral else None,
        )

    def step(self, state: TyreState, sample: Sample, dt: float) -> tuple[TyreState, Estimate]:
        kf_state, loads = self.kf.step(state.kf, sample, dt)
        rate = np.nan if sample.rates is None else float(sample.rates[2])
        loaded = self.kf.state_mass_properties(kf_state)[None]
        inputs = Inputs(
            spin=_given(sample.spin, 4), torque=_given(sample.torque, 4),
            steer=np.nan if sample.steer is None else float(sample.steer), rate=rate,
            speed=float(sample.vx),
            sums=self.force_sums(np.asarray(sample.d)[None], np.asarray(sample.acc)[None],
                                 [sample.vx], [rate], loaded)[0],
            loads=loads.loads[0], mass_properties=loaded[0],
        )  # fmt: skip
        core, *outputs = self.core_step(state.core, inputs, float(dt))
        rows = [np.asarray(o, float).reshape(1, 4) for o in outputs[:4]]
        return TyreState(kf=kf_state, core=core), self._estimate(loads, *rows, outputs[4])

    def run(self, signals: Signals) -> Estimate:
        """The whole log: the KF's ``run`` for the loads, then the observers' step looped in
        compiled C (the same numbers as :meth:`step`)."""
        require_wheel_channels(signals)
        loads = self.kf.run(signals)
        n = len(signals)
        rates = np.full(n, np.nan) if signals.rates is None else signals.rates[:, 2]
        loaded = self.mass_properties_of(loads)
        sums = self.force_sums(signals.d, signals.acc, signals.vx, rates, loaded)
        dts = np.concatenate([np.diff(signals.t)[:1], np.diff(signals.t)])
        unique, which = np.unique(np.round(dts, 9), return_inverse=True)
        observer = np.array([self.observer_input(dt) for dt in unique])[which]
        wheels = np.column_stack([signals.spin, signals.torque, signals.steer])
        arguments = _core_arguments(wheels, sums, rates, signals.vx, loads.loads, loaded)
        _, _, (fx, fx_std, fy, fy_std, high_slip) = self._loop(
            [np.zeros(CORE.size)], [], [*arguments, dts[:, None], observer]
        )
        return self._estimate(loads, fx, fx_std, fy, fy_std, high_slip)


def _core_arguments(wheels, sums, rates, speeds, loads, mass_properties) -> list[np.ndarray]:
    """Per-sample inputs of the core step before ``dt``: values with 0 where missing and
    their validity flags (n rows each), then the KF's loads and mass properties."""

    def split(values):
        values = np.asarray(values, float).reshape(len(values), -1)
        valid = np.isfinite(values)
        return np.where(valid, values, 0.0), valid.astype(float)

    return [*split(wheels), *split(sums), *split(rates), *split(speeds),
            np.asarray(loads, float), np.asarray(mass_properties, float)]  # fmt: skip


def lateral_split(vehicle: Vehicle, split: LateralSplit | None) -> LateralSplit:
    """The left/right split: ``split`` where given, else the tyres' load sensitivity if the
    file has ``[cornering]``, else the paper's normal-load share (a one-line error for
    ``TYRE`` without ``[cornering]``)."""
    if split is None:
        return LateralSplit.LOAD if vehicle.cornering is None else LateralSplit.TYRE
    if split is LateralSplit.TYRE and vehicle.cornering is None:
        raise TyreInputError(
            f"vehicle '{vehicle.name}' has no [cornering] section: the tyre split needs the "
            "tyres' load sensitivity (see 'wheelload vehicle --template'), or use "
            "split=LateralSplit.LOAD"
        )
    return split


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
        kf_state, loads = self.kf.step(state.kf, sample, dt)
        rate = np.nan if sample.rates is None else float(sample.rates[2])
        sums = self.force_sums(np.asarray(sample.d)[None], np.asarray(sample.acc)[None],
                               [sample.vx], [rate],
                               self.kf.state_mass_properties(kf_state)[None])  # fmt: skip
        split = [load_share_split(sums[:, axis], loads.loads) for axis in (0, 1)]
        return replace(state, kf=kf_state), replace(loads, fx=split[0], fy=split[1])

    def run(self, signals: Signals) -> Estimate:
        loads = self.kf.run(signals)
        rates = np.full(len(signals), np.nan) if signals.rates is None else signals.rates[:, 2]
        sums = self.force_sums(signals.d, signals.acc, signals.vx, rates,
                               self.mass_properties_of(loads))  # fmt: skip
        split = [load_share_split(sums[:, axis], loads.loads) for axis in (0, 1)]
        return replace(loads, fx=split[0], fy=split[1])


def _pid(vehicle: Vehicle, settings: TyreSettings = TyreSettings()) -> TyreForces:
    method = TyreForces(vehicle, settings, lateral=False)
    method.name = "tyre-pid"
    return method


def _lateral(vehicle: Vehicle, settings: TyreSettings = TyreSettings()) -> TyreForces:
    method = TyreForces(vehicle, settings, longitudinal=False)
    method.name = "tyre-lateral"
    return method


@dataclass(frozen=True, kw_only=True)
class TyreOptions:
    """Options of ``tyre-pid`` and ``tyre-lateral`` (``build(name, vehicle, **options)``)."""

    settings: TyreSettings = TyreSettings()  # observer, filter noise, high slip, split


@dataclass(frozen=True, kw_only=True)
class TyreForcesOptions(TyreOptions):
    """Options of ``tyre-forces`` and ``tyre-rigid``."""

    longitudinal: bool = True  # report F_x
    lateral: bool = True  # report F_y


INFO = (
    MethodInfo(
        name="tyre-pid",
        description="F_x per wheel: PI spin observer on the wheel dynamics, KF loads",
        reference="corner-based paper §III-A, eq. 1, 4-9",
        build=_pid,
        options=TyreOptions,
    ),
    MethodInfo(
        name="tyre-lateral",
        description="F_y per wheel: adaptive KF on axle forces and yaw rate, KF loads",
        reference="corner-based paper §III-B, eq. 2-3, 10-16, §IV covariance switching",
        build=_lateral,
        options=TyreOptions,
    ),
    MethodInfo(
        name="tyre-forces",
        description="F_x, F_y, F_z per wheel with sigma: KF loads + tyre-pid + tyre-lateral",
        reference="corner-based paper §III; road-angle paper §III (vertical block feeds "
        "the lateral block)",
        build=TyreForces,
        options=TyreForcesOptions,
    ),
    MethodInfo(
        name="tyre-rigid",
        description="baseline: m a_x, m a_y (road frame, drag) split by the KF's load share",
        reference="rigid-body baseline (corner-based paper eq. 2, load-share split)",
        build=RigidSplit,
        options=TyreForcesOptions,
    ),
)
