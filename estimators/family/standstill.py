r"""Standstill mass and CG from logs at rest on one or more slopes (ycoo-umvf paper §5).

Each log contributes the mean loads and specific force of its samples at rest
(speed below ``max_speed``, after ``settle`` seconds of each still period);
weighted Gauss-Newton on the residual of
:func:`~wheelload.models.family.standstill.standstill_residual_function` (its
CasADi Jacobians) gives the whole-vehicle mass, CG distance to the front
axle, lateral CG offset and CG height.

Uncertainty: each log's three residual rows get the covariance of the
sensor errors propagated through the model's Jacobians, a load error of
``load_std`` per wheel (suspension calibration) and an accelerometer error of
``accel_std`` per axis (the turn-on bias: it does not average out), plus the
standard errors of the means. The parameter covariance is
:math:`(J^\top W J)^{-1}`, scaled up by :math:`\chi^2/\nu` when the fit has
:math:`\nu > 0` degrees of freedom and a worse fit than the error model
predicts. With a single attitude only three of the four unknowns are
determined, and the fit says so.

Example
-------
>>> result = weigh([read_log("level.csv"), read_log("slope.csv")], vehicle)
>>> result.mass, result.mass_std
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.quarter_car import unsprung_masses
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, ModelParameters, Vehicle, vehicle_mass_centre
from wheelload.models.family.quarter_car import tyre_load_function
from wheelload.models.family.standstill import UNKNOWNS, standstill_residual_function
from wheelload.models.inputs import INPUTS, SPECIFIC_FORCE, input_index
from wheelload.models.terms import GATES, gates_function

MAX_ITERATIONS = 30
CONDITION_LIMIT = 1e10  # of the normal matrix: beyond it an unknown is not determined


class WeighError(ValueError):
    """Logs that cannot be weighed: names the log and the reason."""


@dataclass(frozen=True, kw_only=True)
class WeighSettings:
    """At-rest selection and the sensor error model of the uncertainty."""

    max_speed: float = 0.3  # m/s, |vx| below which a sample is at rest
    settle: float = 1.0  # s dropped at the start of each still period
    load_std: float = 10.0  # N per wheel, suspension calibration (1 sigma)
    accel_std: float = 0.05  # m/s^2 per axis, accelerometer bias (5 mg, 1 sigma)

    def __post_init__(self) -> None:
        for key in ("max_speed", "load_std", "accel_std"):
            if not getattr(self, key) > 0:
                raise ValueError(f"weigh setting '{key}' must be > 0, got {getattr(self, key)}")
        if not self.settle >= 0:
            raise ValueError(f"weigh setting 'settle' must be >= 0, got {self.settle}")


@dataclass(frozen=True, kw_only=True)
class Attitude:
    """Mean loads [N] and specific force [m/s^2] of one log at rest, with standard errors.

    ``inputs``: the mean input vector at rest (missing channels 0); ``gates``: the model's
    term gates for the channels the log has.
    """

    source: str
    loads: np.ndarray
    loads_se: np.ndarray
    acc: np.ndarray
    acc_se: np.ndarray
    samples: int
    inputs: np.ndarray
    gates: np.ndarray


@dataclass(frozen=True, kw_only=True)
class WeighResult:
    """Whole-vehicle mass [kg], CG to front axle [m], lateral offset [m] (left +), CG height [m]."""

    values: np.ndarray  # UNKNOWNS order
    covariance: np.ndarray
    attitudes: tuple[Attitude, ...]
    chi2: float
    dof: int

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance))

    def __getattr__(self, name: str) -> float:
        for i, key in enumerate(UNKNOWNS):
            if name == key:
                return float(self.values[i])
            if name == f"{key}_std":
                return float(self.std[i])
        raise AttributeError(name)


def at_rest(signals: Signals, vehicle: Vehicle, settings: WeighSettings) -> Attitude:
    """The mean loads and specific force of the still samples of one log."""
    still = np.abs(signals.vx) < settings.max_speed
    usable = np.zeros(len(signals), bool)
    edges = np.diff(np.concatenate([[0], still.astype(np.int8), [0]]))
    for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        settled = signals.t[start:stop] >= signals.t[start] + settings.settle
        usable[start:stop] = settled
    finite = np.all(np.isfinite(signals.d), axis=1) & np.all(np.isfinite(signals.v), axis=1)
    usable &= finite & np.all(np.isfinite(signals.acc), axis=1)
    count = int(usable.sum())
    if count < 2:
        raise WeighError(
            f"{signals.source}: no stretch at rest (|vx| < {settings.max_speed} m/s for more than "
            f"{settings.settle} s with all travels and accelerations); record the car standing"
        )
    p = ModelParameters.from_vehicle(vehicle).vector()
    acc = signals.acc[usable]
    a_u = np.repeat(acc[:, 2:3] - GRAVITY, 4, axis=1)
    loads_of = tyre_load_function().map(count)
    loads = np.asarray(
        loads_of(signals.d[usable].T, signals.v[usable].T, a_u.T, unsprung_masses(vehicle), p)
    ).T
    u = input_matrix(signals, RateDerivativeFilter.of(vehicle))[:, usable].T
    valid = np.all(np.isfinite(u), axis=0)
    mean_inputs = np.where(valid, np.nanmean(np.where(np.isfinite(u), u, 0.0), axis=0), 0.0)
    gates = np.asarray(gates_function()(valid.astype(float), p)[0], float).ravel()
    return Attitude(
        source=signals.source,
        loads=loads.mean(axis=0),
        loads_se=loads.std(axis=0) / np.sqrt(count),
        acc=acc.mean(axis=0),
        acc_se=acc.std(axis=0) / np.sqrt(count),
        samples=count,
        inputs=mean_inputs,
        gates=gates,
    )


def weigh(
    logs: list[Signals], vehicle: Vehicle, settings: WeighSettings = WeighSettings()
) -> WeighResult:
    """Mass, CG position and height from logs at rest (see module docstring)."""
    if not logs:
        raise WeighError("give at least one log at rest")
    attitudes = tuple(at_rest(log, vehicle, settings) for log in logs)
    p = ModelParameters.from_vehicle(vehicle).vector()
    centre = vehicle_mass_centre(vehicle)
    theta = np.array([vehicle.mass.total, centre.lf, 0.0, centre.height])
    F, u, th = ca.SX.sym("F", 4), ca.SX.sym("u", len(INPUTS)), ca.SX.sym("theta", 4)
    gates = ca.SX.sym("gates", len(GATES))
    residual = standstill_residual_function()(F, u, gates, th, p)
    J_acc = ca.jacobian(residual, u)[:, input_index(SPECIFIC_FORCE)]
    model = ca.Function(
        "standstill_fit",
        [F, u, gates, th],
        [residual, ca.jacobian(residual, th), ca.jacobian(residual, F), J_acc],
    )
    for _ in range(MAX_ITERATIONS):
        rows, jac, weights = [], [], []
        for a in attitudes:
            values = model(a.loads, a.inputs, a.gates, theta)
            r, J, J_F, J_a = (np.asarray(m, float) for m in values)
            cov_F = np.diag(settings.load_std**2 + a.loads_se**2)
            cov_a = np.diag(settings.accel_std**2 + a.acc_se**2)
            cov = J_F @ cov_F @ J_F.T + J_a @ cov_a @ J_a.T
            rows.append(r.ravel())
            jac.append(J)
            weights.append(np.linalg.inv(cov))
        r, J = np.concatenate(rows), np.vstack(jac)
        W = np.zeros((len(r), len(r)))
        for i, w in enumerate(weights):
            W[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = w
        normal = J.T @ W @ J
        if np.linalg.cond(normal) > CONDITION_LIMIT:
            raise WeighError(
                f"{len(attitudes)} log(s) at rest hold only one attitude: the CG distance and "
                "height cannot be separated; add a log at rest on another slope"
            )
        step = np.linalg.solve(normal, -J.T @ W @ r)
        theta = theta + step
        if np.max(np.abs(step) / np.maximum(np.abs(theta), 1.0)) < 1e-12:
            break
    chi2 = float(r @ W @ r)
    dof = len(r) - len(theta)
    covariance = np.linalg.inv(normal)
    if dof > 0 and chi2 / dof > 1.0:
        covariance = covariance * chi2 / dof
    return WeighResult(values=theta, covariance=covariance, attitudes=attitudes, chi2=chi2, dof=dof)


def sprung_geometry(vehicle: Vehicle, result: WeighResult) -> dict[str, float]:
    """Vehicle-file values (sprung mass and its CG) equivalent to the weighed whole vehicle.

    Inverts :func:`~wheelload.models.mass_properties.vehicle_mass_centre` with
    the file's unsprung masses and wheel radii.
    """
    m = vehicle.mass
    total = result.mass
    sprung = total - m.unsprung_front - m.unsprung_rear
    spacing = vehicle.geometry.lf + vehicle.geometry.lr
    lf = (result.lf - m.unsprung_rear * spacing / total) * total / sprung
    t = vehicle.tyres
    height = (
        total * result.cg_height
        - m.unsprung_front * t.radius_front
        - m.unsprung_rear * t.radius_rear
    ) / sprung
    return {"total": total, "sprung": sprung, "lf": lf, "lr": spacing - lf, "cg_height": height}
