r"""Unbiased minimum-variance filter with unknown inputs, UMVF (ycoo-umvf paper §4, eq. 17-30).

Per corner, on the reduced quarter-car model (§4: the direction in which both
masses move together is unobservable and removed;
:func:`~wheelload.models.family.quarter_car.reduced_quarter_car_function`), states
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
  model, so the filter's model is the project's suspension model: by
  default the KF's full pseudo-measurement with the vehicle file's terms
  (links, tyre forces, stops; not the hub accelerometers' unsprung term),
  with ``suspension=SuspensionModel.PAPER`` eq. 9 alone
  (:mod:`~wheelload.estimators.family.suspension_model`).
- :math:`a_s` per corner from the body IMU,
  :math:`a_z - g + \dot\omega_x y_i - \dot\omega_y x_i`, the angular
  accelerations by backward differences of the rates (zero without rates).

The numpy functions :func:`discrete_model`, :func:`umvf_update` and
:func:`unknown_input` are the reference implementation of the equations; the
estimator's step is the same algorithm as one CasADi Function (rank-one
pseudo-inverses in closed form), looped in compiled C by ``run``, and the
tests check that the two agree.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import step_flags, step_name
from wheelload.estimators.family.quarter_car import unsprung_masses
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import equilibrium_residual, suspension_loads
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.body_attitude import corner_positions, corner_vertical_acceleration
from wheelload.models.conventions import WHEELS
from wheelload.models.family.quarter_car import reduced_quarter_car_function
from wheelload.models.input_validity import MAX_INTERVAL, interval_is_valid, sanitise

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
    import scipy.linalg  # imported where used: listing the methods stays fast

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


def _corner_step(x, P, residual, u_prev, model, constants, y, u, Q, R):
    """Eq. (19)-(29) for one corner as SX: ``(x, P, residual, e)``; ``model = (A, B, H)``."""
    A, B, H = model
    C, G, D = constants
    x_pred = ca.mtimes(A, x) + B * u_prev
    P_pred = ca.mtimes([A, P, A.T]) + Q
    R_tilde = ca.mtimes([C, P_pred, C.T]) + R
    R_inv = ca.inv(R_tilde)
    # The structure of the model: f~_z has no feedthrough (G's first column is zero) and both
    # inputs enter the state along one direction (H has rank one), see the module docstring.
    h = H[:, 0]
    Phi = ca.horzcat(G[:, 1], ca.mtimes(C, h))
    target = ca.horzcat(ca.DM.zeros(2, 1), h)
    PCR = ca.mtimes([P_pred, C.T, R_inv])
    Omega = target - ca.mtimes(PCR, Phi)
    L = PCR + ca.mtimes([Omega, ca.inv(ca.mtimes([Phi.T, R_inv, Phi])), Phi.T, R_inv])
    innovation = y - ca.mtimes(C, x_pred) - D * u
    x_new = x_pred + ca.mtimes(L, innovation)
    P_new = (
        ca.mtimes([L, R_tilde, L.T]) - ca.mtimes([P_pred, C.T, L.T]) - ca.mtimes([L, C, P_pred])
        + P_pred
    )  # fmt: skip
    P_new = 0.5 * (P_new + P_new.T)
    # Eq. (27)-(29) with the rank-one pseudo-inverses M+ = M' / |M|_F^2 and row bases.
    H_pinv = H.T / ca.sumsqr(H)
    G_pinv = G.T / ca.sumsqr(G)
    V_H = H[1, :] / ca.norm_2(H[1, :].T)
    V_G = G[0, :] / ca.norm_2(G[0, :].T)
    rhs = ca.vertcat(ca.mtimes([V_H, H_pinv, L, innovation]), ca.mtimes([V_G, G_pinv, residual]))
    e = ca.solve(ca.vertcat(V_H, V_G), rhs)
    residual_new = y - ca.mtimes(C, x_new) - D * u
    return x_new, P_new, residual_new, e


def step_function(
    vehicle: Vehicle, tuning: UmvfTuning, constants, model: SuspensionModel = DEFAULT_MODEL
) -> ca.Function:
    """The four corners' UMVF step (layout of :class:`~.step_method.StepMethod`)."""
    x = ca.SX.sym("x", 2, 4)
    P = ca.SX.sym("P", 2, 8)
    residual = ca.SX.sym("residual", 3, 4)
    memory = ca.SX.sym("memory", 11)  # previous known inputs (4), loads (4), rates (2), started
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    models = ca.SX.sym("models", 10, 4)  # per corner: A (4), B (2), H (4), column-major
    p = ca.SX.sym("p", len(ModelParameters.names()))
    u = sanitise(u_raw, valid)
    d, v, acc, rates = u[0:4], u[4:8], u[8:11], u[12:15]
    ok = interval_is_valid(dt)
    dt_safe = ca.if_else(ok, dt, 1.0)
    u_prev, load_prev, rates_prev, started = memory[0:4], memory[4:8], memory[8:10], memory[10]
    rates_ok = valid[12] * valid[13] * started
    rate_acc = ca.if_else(rates_ok, (rates[0:2] - rates_prev) / dt_safe, ca.DM.zeros(2))
    names = ModelParameters.names()
    static = ca.vertcat(*[p[names.index(f"static_{w}")] for w in WHEELS])
    spring, damper = constants["spring"], constants["damper"]
    z = suspension_loads(model, u, valid, p, unsprung_inertia=False)
    extra = z - static - spring * d - damper * v
    a_s = corner_vertical_acceleration(acc[2], rate_acc[0], rate_acc[1], corner_positions(vehicle))
    Q = ca.diag(ca.vertcat(tuning.travel_density, tuning.travel_rate_density)) * dt_safe
    R = ca.DM(tuning.R)
    columns = {"x": [], "P": [], "residual": [], "u": [], "load": []}
    wheel_skipped = []
    for i in range(4):
        corner_ok = ok * valid[i] * valid[4 + i] * valid[10]
        corner = models[:, i]
        corner_model = (ca.reshape(corner[0:4], 2, 2), corner[4:6], ca.reshape(corner[6:10], 2, 2))
        y = ca.vertcat(a_s[i], d[i], v[i])
        Pi = P[:, 2 * i : 2 * i + 2]
        x_n, P_n, r_n, e = _corner_step(
            x[:, i], Pi, residual[:, i], u_prev[i], corner_model, constants["CGD"][i], y, extra[i],
            Q, R,
        )  # fmt: skip
        columns["x"].append(ca.if_else(corner_ok, x_n, x[:, i]))
        columns["P"].append(ca.if_else(corner_ok, P_n, Pi))
        columns["residual"].append(ca.if_else(corner_ok, r_n, residual[:, i]))
        columns["u"].append(ca.if_else(corner_ok, extra[i], u_prev[i]))
        columns["load"].append(ca.if_else(corner_ok, e[0] + static[i], load_prev[i]))
        wheel_skipped.append(1 - corner_ok)
    loads = ca.vertcat(*columns["load"])
    rates_new = ca.if_else(ok * valid[12] * valid[13], rates[0:2], rates_prev)
    memory_new = ca.vertcat(
        *columns["u"], loads, rates_new, ca.if_else(ok * valid[12] * valid[13], 1, started)
    )
    residual_eq, eq_ok = equilibrium_residual(model, u, valid, p, loads)
    rejected = 1 - ok
    missing = ca.fmax(1 - eq_ok, rejected)
    flag_value = step_flags(wheel_skipped, missing, rejected)
    return ca.Function(
        step_name("wheelload_umvf_step", model),
        [x, P, residual, memory, u_raw, valid, dt, models, p],
        [
            ca.horzcat(*columns["x"]), ca.horzcat(*columns["P"]),
            ca.horzcat(*columns["residual"]), memory_new, loads, ca.DM.zeros(4), residual_eq,
            flag_value,
        ],
        ["x", "P", "residual", "memory", "u", "u_valid", "dt", "models", "p"],
        ["x_next", "P_next", "residual_next", "memory_next", "loads", "std", "residual_eq",
         "flags"],
    )  # fmt: skip


class Umvf(FamilyMethod):
    """UMVF tyre-load estimator on each corner (eq. 17-30); compiled loop.

    The discrete model of each corner (``A, B, H``: a matrix exponential) is
    computed once per distinct sample interval and fed in per sample.
    """

    name = "UMVF"
    has_std = False
    interval_names = ("models",)

    def __init__(
        self,
        vehicle: Vehicle,
        tuning: UmvfTuning = UmvfTuning(),
        *,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        self.tuning = tuning
        super().__init__(vehicle, suspension=suspension)

    @functools.cached_property
    def static(self) -> np.ndarray:
        """Static load of each corner [N]."""
        return np.array(self.parameters.static(), float)

    @functools.cached_property
    def unsprung(self) -> np.ndarray:
        return unsprung_masses(self.vehicle)

    @functools.cached_property
    def sprung(self) -> np.ndarray:
        """Sprung mass each corner carries [kg]: its static load less its unsprung mass."""
        return self.static / GRAVITY - self.unsprung

    @functools.cached_property
    def _linear_suspension(self) -> tuple[np.ndarray, np.ndarray]:
        """Spring rate and mean damper rate of each corner (the reduced model's ``k_s, b_s``)."""
        axles = [self.vehicle.suspension.front] * 2 + [self.vehicle.suspension.rear] * 2
        spring = np.array([a.spring_rate for a in axles])
        damper = np.array([0.5 * (a.damper_push + a.damper_pull) for a in axles])
        return spring, damper

    @functools.cached_property
    def _continuous(self) -> list[tuple[np.ndarray, ...]]:
        """Per corner the continuous reduced quarter car ``(A, H, C, G, B, D)``."""
        spring, damper = self._linear_suspension
        reduced = reduced_quarter_car_function()
        continuous = [
            tuple(
                np.asarray(m, float).ravel() if m.shape[1] == 1 else np.asarray(m, float)
                for m in reduced([self.sprung[i], self.unsprung[i], spring[i], damper[i]])
            )
            for i in range(4)
        ]
        for _, H, _, G, _, _ in continuous:
            if np.any(G[:, 0]) or np.linalg.matrix_rank(H) != 1:
                raise ValueError("UMVF: the reduced quarter car lost its input structure")
        return continuous

    def build_step(self) -> ca.Function:
        spring, damper = self._linear_suspension
        constants = {
            "spring": ca.DM(spring),
            "damper": ca.DM(damper),
            "CGD": [(ca.DM(C), ca.DM(G), ca.DM(D)) for _, _, C, G, _, D in self._continuous],
        }
        return step_function(self.vehicle, self.tuning, constants, self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        P0 = np.diag(np.square(self.tuning.initial_std))
        return (
            np.zeros((2, 4)),
            np.tile(P0, (1, 4)),
            np.zeros((3, 4)),
            np.concatenate([np.zeros(4), self.static, np.zeros(3)]),
        )

    def fixed_arrays(self) -> tuple[np.ndarray, ...]:
        return (self.parameters.vector(),)

    @functools.lru_cache(maxsize=64)  # noqa: B019  (one model per sample interval)
    def _models(self, dt: float) -> np.ndarray:
        """Per corner ``A, B, H`` over ``dt`` (column-major), shape (10, 4)."""
        if not (np.isfinite(dt) and 0.0 < dt < MAX_INTERVAL):
            return np.zeros((10, 4))
        columns = []
        for continuous in self._continuous:
            model = discrete_model(continuous, dt)
            columns.append(
                np.concatenate([model.A.ravel(order="F"), model.B, model.H.ravel(order="F")])
            )
        return np.column_stack(columns)

    def interval_inputs(self, dt: np.ndarray) -> list[np.ndarray]:
        keys = np.round(np.asarray(dt, float), 7)
        unique, index = np.unique(keys, return_inverse=True)
        table = np.array([self._models(float(k)).ravel(order="F") for k in unique])
        return [table[index]]


@dataclass(frozen=True, kw_only=True)
class UmvfOptions:
    """Options of the UMVF (``build("umvf", vehicle, **options)``)."""

    tuning: UmvfTuning = UmvfTuning()  # noise of the accelerometer, travel and rate


INFO = MethodInfo(
    name="umvf",
    description="unbiased minimum-variance unknown-input filter per corner, reduced quarter car",
    reference="ycoo-umvf paper (Energies 2021, 14, 2378) §4, eq. 17-30",
    build=Umvf,
    options=UmvfOptions,
    model_choice=True,
)
