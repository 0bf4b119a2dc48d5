r"""Unbiased minimum-variance filter with unknown inputs, UMVF (ycoo-umvf paper §4, eq. 17-30).

Per corner, on the reduced quarter-car model (§4: the direction in which both
masses move together is unobservable and removed;
:func:`~wheelload.models.quarter_car.reduced_quarter_car_function`), states
:math:`x = [\tilde q, \dot q]`, unknown inputs
:math:`e = [\tilde f_z, \Delta f_z]`, measurements
:math:`y = [a_s, \tilde q, \dot q]`, discretised with the inputs held over the
interval:

.. math::
    x_{k+1} = A x_k + B u_k + H e_k, \qquad y_k = C x_k + D u_k + G e_k

Prediction (eq. 19-20), gain under the unbiasedness constraint
:math:`L\Phi = [0, H]` (eq. 21-24), update (eq. 25-26), and the unknown input
from the two partial estimates (eq. 27-29):

.. math::
    \begin{bmatrix} V_H^\top \\ V_G^\top \end{bmatrix} \hat e_k =
    \begin{bmatrix} V_H^\top H^\dagger L_{k+1}(y_{k+1} - C\hat x_{k+1|k} - D u_{k+1}) \\
                    V_G^\top G^\dagger (y_k - C \hat x_{k|k} - D u_k) \end{bmatrix}

so the estimate of :math:`e_k` is available one sample later (the load is
reported with a one-sample delay). The load is :math:`\hat f_z = \hat{\tilde f}_z
+ (m_s + m_u) g`, the static load of the suspension model.

Adaptations:

- Both forces reach the state through the same direction (:math:`H` has rank
  one), so :math:`\Phi = [-G, CH]` of eq. (22) is rank deficient and eq. (24)
  cannot be inverted as printed. Removing the zero column of :math:`G` (as
  the paper does for :math:`G_d`, eq. 18) and keeping one basis column
  :math:`h` of :math:`H` gives :math:`\Phi_r = [G_d, C h]` with the same
  constraint set (:math:`L G_d = 0`, :math:`L C h = h`); eq. (24) is applied
  with :math:`\Phi_r`, the target :math:`[0, h]`.
- Eq. (24) is used with :math:`+\Omega`: as printed (:math:`-\Omega`) the gain
  gives :math:`L\Phi = 2PC^\top\tilde R^{-1}\Phi - [0, H]`, not the
  unbiasedness constraint.
- The known input :math:`u` is the suspension force beyond the linear spring
  and mean damper rate (anti-roll bar, damper asymmetry) from the suspension
  model, so the filter's model is the project's suspension model.
- :math:`a_s` per corner from the body IMU,
  :math:`a_z - g + \dot\omega_x y_i - \dot\omega_y x_i`, the angular
  accelerations by backward differences of the rates (zero without rates).

Per-sample numpy, not compiled: about 1 s for a 90 s lap at 100 Hz.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.linalg

from wheelload.estimators.protocol import step_through
from wheelload.estimators.registry import MethodInfo
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import MAX_INTERVAL, Sample
from wheelload.models import GRAVITY, ModelParameters, Vehicle, equilibrium_function
from wheelload.models.body_attitude import corner_positions, corner_vertical_acceleration
from wheelload.models.quarter_car import reduced_quarter_car_function
from wheelload.models.suspension import suspension_function

RANK_TOLERANCE = 1e-9


@dataclass(frozen=True, kw_only=True)
class UmvfTuning:
    """Noise of the UMVF: measurement standard deviations and process noise densities."""

    acceleration_std: float = 0.5  # m/s^2, a_s: IMU noise plus the rigid-body reconstruction
    travel_std: float = 2e-4  # m
    travel_rate_std: float = 0.02  # m/s, derived by a filtered differentiator
    travel_density: float = 1e-6  # m^2/s
    travel_rate_density: float = 1e-2  # m^2/s^3
    initial_std: tuple[float, float] = (1e-3, 0.05)  # m, m/s

    def __post_init__(self) -> None:
        for key in ("acceleration_std", "travel_std", "travel_rate_std"):
            if not getattr(self, key) > 0:
                raise ValueError(f"UMVF tuning '{key}' must be > 0, got {getattr(self, key)}")

    @property
    def R(self) -> np.ndarray:
        return np.diag([self.acceleration_std, self.travel_std, self.travel_rate_std]) ** 2

    def Q(self, dt: float) -> np.ndarray:
        return np.diag([self.travel_density, self.travel_rate_density]) * dt


@dataclass(frozen=True, kw_only=True)
class DiscreteModel:
    """The reduced quarter car over one interval, with its constraint and input-recovery data."""

    A: np.ndarray
    B: np.ndarray  # (2,) known input
    H: np.ndarray
    C: np.ndarray
    D: np.ndarray  # (3,)
    G: np.ndarray
    Phi: np.ndarray  # reduced constraint matrix [G_d, C h]
    target: np.ndarray  # [0, h]
    H_pinv: np.ndarray
    G_pinv: np.ndarray
    V: np.ndarray  # [V_H'; V_G'] (eq. 29)
    V_H: np.ndarray
    V_G: np.ndarray


def _row_basis(M: np.ndarray) -> np.ndarray:
    """Orthonormal rows spanning the row space of ``M`` (eigenvectors of M^+ M, eigenvalue 1)."""
    _, s, vt = np.linalg.svd(M)
    return vt[: int(np.sum(s > RANK_TOLERANCE * max(s.max(), 1e-300)))]


def _column_basis(M: np.ndarray) -> np.ndarray:
    u, s, _ = np.linalg.svd(M)
    return u[:, : int(np.sum(s > RANK_TOLERANCE * max(s.max(), 1e-300)))] * s[:1]


def discrete_model(continuous: tuple[np.ndarray, ...], dt: float) -> DiscreteModel:
    """Inputs held over ``dt`` (matrix exponential of the augmented system)."""
    A, H, C, G, B, D = continuous
    n, m = A.shape[0], H.shape[1] + 1
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A * dt
    M[:n, n:] = np.column_stack([H, B]) * dt
    E = scipy.linalg.expm(M)
    Ad, inputs = E[:n, :n], E[:n, n:]
    Hd, Bd = inputs[:, :-1], inputs[:, -1]
    G_d = G[:, np.linalg.norm(G, axis=0) > 0]
    h = _column_basis(Hd)
    Phi = np.column_stack([G_d, C @ h])
    target = np.column_stack([np.zeros((n, G_d.shape[1])), h])
    V_H, V_G = _row_basis(Hd), _row_basis(G)
    return DiscreteModel(
        A=Ad, B=Bd, H=Hd, C=C, D=D, G=G, Phi=Phi, target=target,
        H_pinv=np.linalg.pinv(Hd), G_pinv=np.linalg.pinv(G),
        V=np.vstack([V_H, V_G]), V_H=V_H, V_G=V_G,
    )  # fmt: skip


def umvf_update(x, P, u_prev, u, y, model: DiscreteModel, Q, R):
    """Eq. (19)-(26): ``(x_pred, x, P, L, innovation)`` after measurement ``y``."""
    x_pred = model.A @ x + model.B * u_prev
    P_pred = model.A @ P @ model.A.T + Q
    C, Phi = model.C, model.Phi
    R_tilde = C @ P_pred @ C.T + R
    R_inv = np.linalg.inv(R_tilde)
    PCR = P_pred @ C.T @ R_inv
    Omega = model.target - PCR @ Phi
    # Eq. (24) prints '- Omega ...': with Omega of eq. (23) that gives L Phi = 2 P C' R~^-1 Phi
    # - [0, H]; the plus sign gives the constraint L Phi = [0, H] that makes x unbiased.
    L = PCR + Omega @ np.linalg.solve(Phi.T @ R_inv @ Phi, Phi.T @ R_inv)
    innovation = y - C @ x_pred - model.D * u
    x_new = x_pred + L @ innovation
    P_new = L @ R_tilde @ L.T - P_pred @ C.T @ L.T - L @ C @ P_pred + P_pred
    P_new = 0.5 * (P_new + P_new.T)
    return x_new, P_new, L, innovation


def unknown_input(model: DiscreteModel, L, innovation, previous_residual) -> np.ndarray:
    """Eq. (27)-(29): the unbiased estimate of the previous sample's unknown input."""
    rhs = np.concatenate(
        [
            model.V_H @ model.H_pinv @ (L @ innovation),
            model.V_G @ model.G_pinv @ previous_residual,
        ]
    )
    return np.linalg.lstsq(model.V, rhs, rcond=None)[0]


@dataclass(frozen=True, kw_only=True)
class UmvfState:
    """Per corner: state, covariance, previous measurement residual and input; previous rates."""

    x: np.ndarray  # (4, 2)
    P: np.ndarray  # (4, 2, 2)
    residual: np.ndarray  # (4, 3): y_k - C x_k|k - D u_k
    u: np.ndarray  # (4,) known input of the previous sample
    load: np.ndarray  # (4,) last load estimate
    rates: np.ndarray  # (3,) previous body rates (NaN: none yet)


class Umvf:
    """UMVF tyre-load estimator on each corner (eq. 17-30); per-sample numpy."""

    name = "UMVF"

    def __init__(self, vehicle: Vehicle, tuning: UmvfTuning = UmvfTuning()) -> None:
        self.vehicle = vehicle
        self.tuning = tuning
        self.parameters = ModelParameters.from_vehicle(vehicle)
        self.p = self.parameters.vector()
        self.static = np.array(self.parameters.static(), float)
        mass = vehicle.mass
        self.unsprung = np.array([mass.unsprung_front] * 2 + [mass.unsprung_rear] * 2) / 2
        self.sprung = self.static / GRAVITY - self.unsprung
        axles = [vehicle.suspension.front] * 2 + [vehicle.suspension.rear] * 2
        self.spring = np.array([a.spring_rate for a in axles])
        self.damper = np.array([0.5 * (a.damper_push + a.damper_pull) for a in axles])
        reduced = reduced_quarter_car_function()
        self._continuous = [
            tuple(
                np.atleast_1d(np.asarray(m, float).squeeze())
                if m.shape[1] == 1
                else np.asarray(m, float)
                for m in reduced([self.sprung[i], self.unsprung[i], self.spring[i], self.damper[i]])
            )
            for i in range(4)
        ]
        d, v, acc, rate_acc = (
            ca.SX.sym(k, n) for k, n in (("d", 4), ("v", 4), ("acc", 3), ("w", 2))
        )
        p = ca.SX.sym("p", len(self.p))
        suspension = suspension_function()(d, v, p)
        extra = suspension - ca.DM(self.static) - self.spring * d - self.damper * v
        a_s = corner_vertical_acceleration(
            acc[2], rate_acc[0], rate_acc[1], corner_positions(vehicle)
        )
        self._measurements = ca.Function(
            "umvf_measurements", [d, v, acc, rate_acc, p], [extra, a_s]
        )
        self._equilibrium = equilibrium_function()

    @functools.lru_cache(maxsize=16)  # noqa: B019  (one model per sample interval)
    def _models(self, dt: float) -> tuple[DiscreteModel, ...]:
        return tuple(discrete_model(self._continuous[i], dt) for i in range(4))

    def initial_state(self) -> UmvfState:
        P0 = np.diag(np.square(self.tuning.initial_std))
        return UmvfState(
            x=np.zeros((4, 2)),
            P=np.tile(P0, (4, 1, 1)),
            residual=np.zeros((4, 3)),
            u=np.zeros(4),
            load=self.static.copy(),
            rates=np.full(3, np.nan),
        )

    def step(self, state: UmvfState, sample: Sample, dt: float) -> tuple[UmvfState, Estimate]:
        """One sample on each corner; returns the estimate of the previous sample's load."""
        acc = np.asarray(sample.acc, float)
        flags = 0
        if not (np.isfinite(dt) and 0.0 < dt < MAX_INTERVAL):
            return state, self._estimate(
                state.load, acc, sample.vx, int(StepFlag.STEP_REJECTED) | 0x7F
            )
        rates = np.full(3, np.nan) if sample.rates is None else np.asarray(sample.rates, float)
        rate_acc = (rates[:2] - state.rates[:2]) / dt
        rate_acc = np.where(np.isfinite(rate_acc), rate_acc, 0.0)
        d, v = np.asarray(sample.d, float), np.asarray(sample.v, float)
        corner_ok = np.isfinite(d) & np.isfinite(v) & np.isfinite(acc[2])
        extra, a_s = (
            np.asarray(m, float).ravel()
            for m in self._measurements(
                np.nan_to_num(d), np.nan_to_num(v), np.nan_to_num(acc), rate_acc, self.p
            )
        )
        # Intervals are rounded to 0.1 us so that a log's jittered intervals share one model.
        models = self._models(round(float(dt), 7))
        x, P, residual, u_all, load = (
            state.x.copy(), state.P.copy(), state.residual.copy(), state.u.copy(),
            state.load.copy(),
        )  # fmt: skip
        Q, R = self.tuning.Q(dt), self.tuning.R
        for i in range(4):
            if not corner_ok[i]:
                flags |= int(list(StepFlag)[i])
                continue
            y = np.array([a_s[i], d[i], v[i]])
            model = models[i]
            x_new, P_new, L, innovation = umvf_update(
                x[i], P[i], u_all[i], extra[i], y, model, Q, R
            )
            e = unknown_input(model, L, innovation, residual[i])
            x[i], P[i] = x_new, P_new
            residual[i] = y - model.C @ x_new - model.D * extra[i]
            u_all[i] = extra[i]
            load[i] = e[0] + self.static[i]
        new_rates = np.where(np.isfinite(rates), rates, state.rates)
        new = UmvfState(x=x, P=P, residual=residual, u=u_all, load=load, rates=new_rates)
        return new, self._estimate(load, acc, sample.vx, flags)

    def _estimate(self, load, acc, vx, flags: int) -> Estimate:
        load = np.where(np.isfinite(load), load, self.static)
        if np.all(np.isfinite(acc)) and np.isfinite(vx):
            A, b = (np.asarray(m, float) for m in self._equilibrium(acc, vx, self.p))
            residual = b.ravel() - A @ load
        else:
            residual = np.zeros(3)
            flags |= int(StepFlag.VERTICAL_SKIPPED | StepFlag.PITCH_SKIPPED | StepFlag.ROLL_SKIPPED)
        return Estimate(
            t=np.array([np.nan]),
            loads=load.reshape(1, 4),
            std=np.zeros((1, 4)),
            residual=residual.reshape(1, 3),
            flags=np.array([flags], dtype=np.int64),
            has_std=False,
        )

    def run(self, signals: Signals) -> Estimate:
        """Every sample of a log through :meth:`step` from a fresh state."""
        return step_through(self, signals)


INFO = MethodInfo(
    name="umvf",
    description="unbiased minimum-variance unknown-input filter per corner, reduced quarter car",
    reference="ycoo-umvf paper (Energies 2021, 14, 2378) §4, eq. 17-30",
    build=Umvf,
)
