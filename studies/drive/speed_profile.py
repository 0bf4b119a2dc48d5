r"""Quasi-steady-state lap speed profile: corner limits, forward and backward passes.

Grip (:func:`cornering_friction`): the lateral friction coefficient the
limiting axle of the plant's tyres gives at a steady lateral acceleration,
with the load transfer of a rigid body rolling about the ground, shared by the
axles' roll stiffnesses :math:`K_\phi = (k_s/2 + \gamma k_{arb}) t^2`, and the
magic-formula peak :math:`D = \mu_0 (1 + p_{D2}\, df_z) F_z` of each tyre:

.. math:: \mu_{axle}(a_y) = \frac{\sum_{L,R} D(F_{z,i}(a_y))}{m_{axle}\, g},
          \quad \mu_{eff} = \min_{axle} \mu_{axle}(\mu_{eff} g)

(a fixed point). The profile plans with :math:`\mu = c\, \mu_{eff}`, the
margin :math:`c < 1` leaving the driver room to correct.

Corner limit with aerodynamic lift :math:`L = q c_L v^2`, :math:`q = \rho A / 2`,
and the vertical curvature :math:`z''` of the road (a dip loads the tyres):
:math:`m v^2 |\kappa| = \mu (m g + m z'' v^2 - q c_L v^2)`, so

.. math:: v^2 = \frac{\mu g}{|\kappa| - \mu z'' + \mu q c_L / m}.

Forward pass :math:`d(v^2)/ds = 2 a` with
:math:`a = \min(P / (m v), \mu g\, e) - D/m - g \sin\gamma - f_r g` and the
friction-ellipse share :math:`e = \sqrt{1 - (v^2 \kappa / (\mu g))^2}`;
backward pass the same with braking :math:`\mu g\, e + D/m + g \sin\gamma + f_r g`
(four-wheel drive, brakes shared by the driver in proportion to the axle loads).
A closed lap is solved on three laps end to end and the middle lap kept, so the
profile is periodic.
"""

from __future__ import annotations

import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.mass_properties import static_loads
from wheelload.models.plant.dynamics import vehicle_plant
from wheelload.models.vehicle.description import Vehicle
from wheelload.studies.drive.roads import Road


def roll_stiffness_share_front(vehicle: Vehicle) -> float:
    r"""Front share of the roll stiffness, :math:`K_{\phi f} / (K_{\phi f} + K_{\phi r})`."""
    g, susp = vehicle.geometry, vehicle.suspension
    front = (0.5 * susp.front.spring_rate + susp.front.arb_ratio * susp.front.arb_rate) * (
        g.track_front**2
    )
    rear = (0.5 * susp.rear.spring_rate + susp.rear.arb_ratio * susp.rear.arb_rate) * (
        g.track_rear**2
    )
    return front / (front + rear)


def axle_friction(vehicle: Vehicle, lateral: float) -> tuple[float, float]:
    """Peak lateral force over axle weight, front and rear, at lateral acceleration ``lateral``."""
    tyre = vehicle_plant(vehicle).tyre
    loads = static_loads(vehicle)
    g = vehicle.geometry
    share = roll_stiffness_share_front(vehicle)
    moment = vehicle.mass.total * g.cg_height * abs(lateral)
    result = []
    for axle, (nominal, track, part) in enumerate(
        (
            (tyre.nominal_load_front, g.track_front, share),
            (tyre.nominal_load_rear, g.track_rear, 1.0 - share),
        )
    ):
        static = loads[2 * axle]
        transfer = part * moment / track
        peak = 0.0
        for fz in (static + transfer, max(static - transfer, 0.0)):
            mu = tyre.friction_y * (1.0 + tyre.friction_load_sensitivity * (fz - nominal) / nominal)
            peak += mu * fz
        result.append(peak / (2.0 * static))
    return result[0], result[1]


def cornering_friction(vehicle: Vehicle) -> float:
    """Effective lateral friction of the limiting axle at its own limit (fixed point)."""
    mu = min(axle_friction(vehicle, 0.0))
    for _ in range(20):
        mu = min(axle_friction(vehicle, mu * GRAVITY))
    return mu


def speed_profile(
    vehicle: Vehicle,
    s: np.ndarray,
    curvature: np.ndarray,
    grade: np.ndarray,
    *,
    friction: float,
    top_speed: float,
) -> np.ndarray:
    """Target speed [m/s] on the uniform grid ``s`` for the planning friction ``friction``."""
    plant = vehicle_plant(vehicle)
    m = vehicle.mass.total
    aero = vehicle.aero
    q = 0.5 * aero.air_density * aero.reference_area
    ds = float(s[1] - s[0])
    vertical = np.gradient(grade, ds)  # z'' [1/m], > 0 in a dip
    mu_g = friction * GRAVITY
    denominator = np.abs(curvature) - friction * vertical + friction * q * aero.lift_coefficient / m
    limit = np.sqrt(mu_g / np.maximum(denominator, mu_g / top_speed**2))
    v = np.minimum(limit, top_speed)
    sin_grade = grade / np.hypot(1.0, grade)
    rolling = plant.tyre.rolling_resistance * GRAVITY
    drag_per_v2 = q * aero.drag_coefficient / m
    power = plant.driveline.max_power / m
    kappa = np.abs(curvature)

    def ellipse(i: int, speed2: float) -> float:
        share = speed2 * kappa[i] / mu_g
        return mu_g * np.sqrt(max(0.0, 1.0 - share * share))

    v2 = v**2
    for i in range(len(s) - 1):  # forward: power and grip
        speed2 = v2[i]
        accel = min(power / max(np.sqrt(speed2), 1.0), ellipse(i, speed2))
        accel -= drag_per_v2 * speed2 + GRAVITY * sin_grade[i] + rolling
        v2[i + 1] = min(v2[i + 1], max(speed2 + 2.0 * accel * ds, 1.0))
    for i in range(len(s) - 1, 0, -1):  # backward: braking
        speed2 = v2[i]
        decel = ellipse(i, speed2) + drag_per_v2 * speed2 + GRAVITY * sin_grade[i] + rolling
        v2[i - 1] = min(v2[i - 1], max(speed2 + 2.0 * decel * ds, 1.0))
    return np.sqrt(v2)


def lap_speed_profile(
    vehicle: Vehicle, road: Road, *, margin: float, top_speed: float = 85.0
) -> np.ndarray:
    """Periodic target speed on ``road.s`` for a closed lap of length ``road.length``.

    The planning friction is ``margin`` times :func:`cornering_friction`.
    """
    surface = road.surface
    ds = float(surface.s[1] - surface.s[0])
    lap = np.arange(0.0, road.length, ds)
    curvature = np.interp(lap, surface.s, surface.curvature, period=road.length)
    grade = np.interp(lap, surface.s, surface.grade, period=road.length)
    three = np.arange(3 * lap.size) * ds
    speed = speed_profile(
        vehicle,
        three,
        np.tile(curvature, 3),
        np.tile(grade, 3),
        friction=margin * cornering_friction(vehicle),
        top_speed=top_speed,
    )
    middle = speed[lap.size : 2 * lap.size]
    return np.interp(surface.s, lap, middle, period=road.length)
