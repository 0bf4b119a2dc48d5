r"""Initial state of the plant: steady motion on the local road plane.

A guess puts the body at its static height, with the attitude of the road
(pitch :math:`-\arctan` grade, roll :math:`\arctan` bank) and the wheels
rolling at ``speed``. Newton's method on the plant's own dynamics function
(:func:`~wheelload.models.plant.dynamics.plant_dynamics`) then moves the unknowns

.. math:: q = (z, \phi, \theta, \psi, v, w, d_i, \omega_i, \kappa_i, \alpha_i)

until, under the held input request :math:`u`,

.. math::
    \dot v = \dot w = \dot p = \dot q = 0, \quad \ddot d_i = 0, \quad
    \dot\omega_i = \dot\kappa_i = \dot\alpha_i = 0, \quad
    \dot n = 0, \quad \dot z = \frac{\partial z_{road}}{\partial s} \dot s

(body and unsprung masses in equilibrium on the road plane, the body moving
parallel to it along the path; the tyres carry the grade and bank components
of gravity through their slip, and on a bank the car crabs: the heading
:math:`\psi` turns uphill by the sideslip). Path position, forward speed
``u`` and the rates ``p, q, r`` stay as given; ``\dot u`` and ``\dot r`` are left to the
driver (the request need not balance drag and grade exactly, nor the yaw
moment of the tyre side forces on a bank). At rest (``speed`` below
:data:`ROLLING`) the tyres cannot carry in-plane force (brake torque fades
with spin), so only the vertical, roll, pitch and suspension coordinates are
solved: the level-ground start is then exact, a grade or bank only its
vertical part.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from wheelload.models.conventions import WHEELS
from wheelload.models.payload import Payload
from wheelload.models.plant.dynamics import (
    INPUT_NAMES,
    STATE,
    STATE_NAMES,
    PlantError,
    corners,
    plant_dynamics,
)
from wheelload.models.plant.road_surface import RoadSurface, road_lookup
from wheelload.models.vehicle.description import Vehicle

ROLLING = 0.5  # m/s, speed from which the tyre slips are solved too
SUSPENSION = ("z", "phi", "theta", "w") + tuple(f"d_{w}" for w in WHEELS)
TYRES = ("psi", "v") + tuple(f"{k}_{w}" for k in ("omega", "kappa", "alpha") for w in WHEELS)
# Residuals: the time derivatives (xdot entries) that vanish, besides the road-following one.
BALANCE = ("w", "p", "q") + tuple(f"dd_{w}" for w in WHEELS)
TYRE_BALANCE = ("n", "v") + tuple(f"{k}_{w}" for k in ("omega", "kappa", "alpha") for w in WHEELS)
TOLERANCE = 1e-9  # residual (m/s^2, rad/s^2, 1/s) at which Newton stops
# Residual accepted when no step along Newton's direction lowers it any more: the
# rounding floor of the dynamics far along a lap (about 1e-9 at s = 11 km).
STALLED = 1e-6
MAX_ITERATIONS = 40


def guess_state(vehicle: Vehicle, road: RoadSurface, s: float, speed: float, n: float = 0.0):
    r"""Start on the road plane under the four wheels: static height, its attitude, zero slip.

    The plane :math:`z = a + b\,x + c\,y` is the least-squares fit of the road heights
    (roughness included) under the four contact points, so that no wheel starts off a
    rough road; on a smooth road it is the road's own grade and bank.
    """
    wheels = corners(vehicle)
    contact = np.array([[1.0, c.x, c.y] for c in wheels])
    lookup = road_lookup(road)  # the plant's own road (linear, extrapolated off the grid)
    heights = []
    for c in wheels:
        elevation, _, bank, _, left, right = np.asarray(lookup(s + c.x)).ravel()
        heights.append(elevation + (n + c.y) * bank + (left if c.left else right))
    (level, grade, bank), *_ = np.linalg.lstsq(contact, np.array(heights), rcond=None)
    x = np.zeros(len(STATE_NAMES))
    x[STATE["s"]] = s
    x[STATE["n"]] = n
    x[STATE["z"]] = level + vehicle.geometry.cg_height
    x[STATE["theta"]] = -np.arctan(grade)
    x[STATE["phi"]] = np.arctan(bank)
    x[STATE["u"]] = speed
    for i, c in enumerate(wheels):
        deflection = c.static_load / c.tyre_rate
        x[STATE["omega_fl"] + i] = speed / (c.radius - deflection / 3.0)
    return x


def _road_slope(road: RoadSurface, s: float, n: float) -> float:
    """:math:`\\partial z_{road} / \\partial s` at (s, n): difference over 0.1 m inside the grid."""
    low = max(s - 0.05, float(road.s[0]))
    high = min(s + 0.05, float(road.s[-1]))
    return float((road.height(high, n) - road.height(low, n)) / (high - low))


def initial_state(
    vehicle: Vehicle,
    road: RoadSurface,
    s: float,
    speed: float,
    n: float = 0.0,
    request: np.ndarray | None = None,
    solve: bool = True,
    payload: Payload | None = None,
) -> np.ndarray:
    """Plant state in steady motion at ``(s, n)`` and ``speed`` under ``request`` (zero if None).

    ``solve=False`` returns the level-ground guess. With ``payload`` the plant carries it
    (:func:`~wheelload.models.plant.dynamics.plant_dynamics`). Raises :class:`PlantError`
    naming ``s`` if Newton's method does not converge.
    """
    x0 = guess_state(vehicle, road, s, speed, n)
    if not solve:
        return x0
    u = np.zeros(len(INPUT_NAMES)) if request is None else np.asarray(request, float)
    if payload is not None:
        u = np.concatenate([u, payload.values])
    rolling = abs(speed) >= ROLLING
    unknowns = SUSPENSION + (TYRES if rolling else ())
    balance = BALANCE + (TYRE_BALANCE if rolling else ())
    index = [STATE[k] for k in unknowns]
    x, inp, xdot, _ = plant_dynamics(vehicle, road, payload is not None)
    q = ca.SX.sym("q", len(index))
    fixed = ca.DM(x0)
    fixed[index] = 0.0
    select = np.zeros((len(STATE_NAMES), len(index)))
    select[index, np.arange(len(index))] = 1.0
    x_of_q = fixed + ca.DM(select) @ q
    rate = ca.substitute(xdot, ca.vertcat(x, inp), ca.vertcat(x_of_q, ca.DM(u)))
    slope = _road_slope(road, s, n)
    follow = rate[STATE["z"]] - slope * rate[STATE["s"]]
    residual = ca.vertcat(follow, *[rate[STATE[k]] for k in balance])
    newton = ca.Function(
        "plant_equilibrium_newton", [q], [residual, ca.jacobian(residual, q)], ["q"], ["r", "J"]
    )
    guess = x0[index]
    for _ in range(MAX_ITERATIONS):
        r_dm, j_dm = newton(guess)
        r, jac = r_dm.full().ravel(), j_dm.full()
        norm = np.abs(r).max()
        if norm < TOLERANCE:
            break
        step = np.linalg.lstsq(jac, -r, rcond=None)[0]  # a wheel off the road: singular
        length = 1.0
        while length > 1e-4:  # backtrack while the residual grows
            trial = guess + length * step
            if np.abs(newton(trial)[0].full()).max() < norm:
                break
            length *= 0.5
        else:
            if norm < STALLED:
                break
        guess = trial
    else:
        raise PlantError(
            f"initial equilibrium at s = {s} m did not converge (residual {norm:.3g}): on a "
            "rough road a wheel may find no steady contact there; try another seed or a "
            "smoother roughness class"
        )
    x_eq = x0.copy()
    x_eq[index] = guess
    return x_eq
