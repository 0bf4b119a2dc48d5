"""Quasi-static synthetic logs: rest, constant acceleration, steady cornering, a slalom.

Reference loads satisfy the rigid-body equilibrium of ``wheelload.models``
exactly, with the one free "warp" direction fixed by sharing the roll moment
between the axles in proportion to the roll stiffness of the suspension
model. The suspension travel is the inverse of the pseudo-measurement model
with optionally mis-stated spring rates (``spring_error``), so the filter
meets a known model mismatch. Because these logs are built from the models
themselves, they exercise the estimators' structure, not the models' signs:
those are pinned by hand derivations and by the full-vehicle plant, the
ground truth for accuracy studies.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.logs.signals import derive_velocities
from wheelload.estimators.types import Signals
from wheelload.models import (
    GATES,
    GRAVITY,
    INPUTS,
    ModelParameters,
    Vehicle,
    equilibrium_function,
    suspension_function,
)
from wheelload.models.inputs import input_vector
from wheelload.models.roll_split import roll_split_function

Profile = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True, kw_only=True)
class Manoeuvre:
    """Time histories of the body-frame specific force and speed."""

    duration: float  # s
    ax: Profile  # m/s^2, without gravity (level road)
    ay: Profile
    vx: Profile


@dataclass(frozen=True, kw_only=True)
class SensorNoise:
    """White noise (1 sigma) added to the logged channels."""

    acceleration: float = 0.0  # m/s^2
    travel: float = 0.0  # m


def rest(duration: float = 10.0) -> Manoeuvre:
    return Manoeuvre(duration=duration, ax=np.zeros_like, ay=np.zeros_like, vx=np.zeros_like)


def constant_acceleration(ax: float = 3.0, duration: float = 8.0, speed: float = 10.0) -> Manoeuvre:
    """Ramp into a constant longitudinal acceleration over 1 s."""
    return Manoeuvre(
        duration=duration,
        ax=lambda t: ax * np.clip(t - 1.0, 0.0, 1.0),
        ay=np.zeros_like,
        vx=lambda t: speed + ax * np.clip(t - 1.0, 0.0, None),
    )


def steady_cornering(ay: float = 6.0, duration: float = 8.0, speed: float = 25.0) -> Manoeuvre:
    """Ramp into a constant left turn (ay > 0) over 1 s at constant speed."""
    return Manoeuvre(
        duration=duration,
        ax=np.zeros_like,
        ay=lambda t: ay * np.clip(t - 1.0, 0.0, 1.0),
        vx=lambda t: np.full_like(t, speed),
    )


def slalom(duration: float = 30.0, speed: float = 25.0) -> Manoeuvre:
    """Weaving at 0.4 Hz with braking and acceleration phases."""
    return Manoeuvre(
        duration=duration,
        ax=lambda t: 2.5 * np.sin(2 * np.pi * t / 15.0),
        ay=lambda t: 6.0 * np.sin(2 * np.pi * 0.4 * t) * np.clip(t / 2.0, 0.0, 1.0),
        vx=lambda t: speed - 2.5 * 15.0 / (2 * np.pi) * (np.cos(2 * np.pi * t / 15.0) - 1.0),
    )


def travel_stiffness(vehicle: Vehicle) -> np.ndarray:
    """:math:`J = \\partial z / \\partial d` (4 x 4) of the suspension model at rest, in N/m."""
    d = ca.SX.sym("d", 4)
    p = ModelParameters.from_vehicle(vehicle).vector()
    u = ca.vertcat(d, ca.DM.zeros(len(INPUTS) - 4))  # at rest; the travel leads INPUTS
    z = suspension_function()(u, ca.DM.zeros(len(GATES)), p)
    return np.asarray(ca.Function("J", [d], [ca.jacobian(z, d)])(np.zeros(4)))


def roll_share_front(vehicle: Vehicle) -> float:
    """Front share of the lateral load transfer: the model's (models/roll_split.py)."""
    return float(ModelParameters.from_vehicle(vehicle).roll_split_front)


def reference_loads(vehicle: Vehicle, acc: np.ndarray, vx: np.ndarray) -> np.ndarray:
    """Loads (n, 4) satisfying :math:`A x = b` with the roll moment shared by roll stiffness."""
    p = ModelParameters.from_vehicle(vehicle).vector()
    n = len(vx)
    u = np.nan_to_num(input_vector(d=np.zeros((n, 4)), acc=acc, vx=vx))
    # The paper's model (every term off): a synthetic log is quasi-static.
    A, b = equilibrium_function().map(n)(u, np.zeros(len(GATES)), p)
    A = np.asarray(A)[:, :4]
    b = np.asarray(b).T
    split = np.asarray(roll_split_function()(p)).reshape(1, 4)
    system = np.vstack([A, split])
    rhs = np.column_stack([b, np.zeros(n)])
    return np.linalg.solve(system, rhs.T).T


def travel_from_loads(vehicle: Vehicle, loads: np.ndarray, spring_error: float) -> np.ndarray:
    """Invert the pseudo-measurement at rest-rate: :math:`d = J^{-1}(F - F_0)`.

    ``spring_error`` scales the spring rates of the generating suspension, so
    that the filter's model is off by that factor.
    """
    axles = {
        axle: _scaled_spring(getattr(vehicle.suspension, axle), spring_error)
        for axle in ("front", "rear")
    }
    generating = vehicle.replace(
        suspension=type(vehicle.suspension)(front=axles["front"], rear=axles["rear"])
    )
    static = np.array(ModelParameters.from_vehicle(generating).static())
    return np.linalg.solve(travel_stiffness(generating), (loads - static).T).T


def _scaled_spring(axle, spring_error: float):
    return dataclasses.replace(axle, spring_rate=axle.spring_rate * (1.0 + spring_error))


def synthetic_log(
    vehicle: Vehicle,
    manoeuvre: Manoeuvre,
    *,
    rate: float = 100.0,
    noise: SensorNoise = SensorNoise(),
    spring_error: float = 0.0,
    seed: int = 0,
) -> Signals:
    """A quasi-static log of ``manoeuvre`` with reference loads (see module docstring)."""
    t = np.arange(0.0, manoeuvre.duration, 1.0 / rate)
    acc = np.column_stack([manoeuvre.ax(t), manoeuvre.ay(t), np.full_like(t, GRAVITY)])
    vx = manoeuvre.vx(t)
    loads = reference_loads(vehicle, acc, vx)
    d = travel_from_loads(vehicle, loads, spring_error)
    rng = np.random.default_rng(seed)
    acc_logged = acc + noise.acceleration * rng.standard_normal(acc.shape)
    d_logged = d + noise.travel * rng.standard_normal(d.shape)
    return Signals(
        t=t,
        vx=vx,
        acc=acc_logged,
        d=d_logged,
        v=derive_velocities(t, d_logged),
        reference=loads,
        velocities_derived=True,
        source="synthetic",
    )
