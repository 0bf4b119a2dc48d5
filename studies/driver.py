r"""Closed-loop driver: preview (pure-pursuit) steering and a speed controller.

Steering aims at the target point a preview distance :math:`L_p = \max(L_0,
T_p u)` ahead on the target path; with :math:`e` its lateral offset and
:math:`\ell` its distance in the vehicle frame, the demanded path curvature is
:math:`c = 2 e / \ell^2` and the road-wheel angle
:math:`\delta = c (L + K_{us} u^2)`, with the linear-bicycle understeer
gradient :math:`K_{us} = (m / L)(l_r / C_f - l_f / C_r)`.

Speed: :math:`F = m (a_{ref} + k_p (v_{ref} - u) + k_i \int (v_{ref} - u))`
plus drag and rolling resistance, split into drive torque (power-limited,
``drive_share_front``) or brake torque (``brake_share_front``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wheelload.models.plant import INPUT_NAMES, STATE, corners, vehicle_plant
from wheelload.models.vehicle import GRAVITY, Vehicle
from wheelload.studies.roads import Road


@dataclass(frozen=True, kw_only=True)
class DriverTuning:
    preview_time: float = 0.35  # s
    preview_min: float = 6.0  # m
    speed_gain: float = 1.5  # 1/s
    speed_integral: float = 0.3  # 1/s^2
    speed_preview: float = 0.3  # s, the speed target is read this far ahead
    max_steer: float = 0.6  # rad, road-wheel angle


def understeer_gradient(vehicle: Vehicle) -> float:
    """Linear-bicycle understeer gradient [rad s^2/m] from the plant's tyre cornering stiffness."""
    tyre = vehicle_plant(vehicle).tyre
    loads = [c.static_load for c in corners(vehicle)]
    stiffness = []
    for load, nominal in ((loads[0], tyre.nominal_load_front), (loads[2], tyre.nominal_load_rear)):
        per_tyre = (
            tyre.cornering_stiffness_y
            * nominal
            * np.sin(2.0 * np.arctan(load / (tyre.cornering_load_y * nominal)))
        )
        stiffness.append(2.0 * per_tyre)
    g = vehicle.geometry
    length = g.lf + g.lr
    return vehicle.mass.total / length * (g.lr / stiffness[0] - g.lf / stiffness[1])


@dataclass(kw_only=True)
class Driver:
    """Driver of one run: call :meth:`inputs` once per output sample with the plant state."""

    vehicle: Vehicle
    road: Road
    speed: np.ndarray  # m/s, target speed on the road grid
    tuning: DriverTuning = field(default_factory=DriverTuning)
    integral: float = 0.0

    def __post_init__(self) -> None:
        self._understeer = understeer_gradient(self.vehicle)
        self._accel = np.gradient(0.5 * self.speed**2, self.road.s)
        g = self.vehicle.geometry
        self._length = g.lf + g.lr
        self._radius = [c.radius for c in corners(self.vehicle)]

    def _point(self, s: float, offset: float):
        road = self.road
        x = np.interp(s, road.s, road.x)
        y = np.interp(s, road.s, road.y)
        heading = np.interp(s, road.s, road.heading)
        return x - offset * np.sin(heading), y + offset * np.cos(heading), heading

    def steer(self, state: np.ndarray) -> float:
        """Road-wheel steer angle [rad] by preview on the target path."""
        s, n, psi, u = (state[STATE[k]] for k in ("s", "n", "psi", "u"))
        x0, y0, heading0 = self._point(s, n)
        heading = heading0 + psi
        preview = max(self.tuning.preview_min, self.tuning.preview_time * u)
        ahead = s + preview
        x1, y1, _ = self._point(ahead, np.interp(ahead, self.road.s, self.road.target))
        dx, dy = x1 - x0, y1 - y0
        lateral = -np.sin(heading) * dx + np.cos(heading) * dy
        curvature = 2.0 * lateral / (dx * dx + dy * dy)
        angle = curvature * (self._length + self._understeer * u * u)
        return float(np.clip(angle, -self.tuning.max_steer, self.tuning.max_steer))

    def force(self, state: np.ndarray, dt: float) -> float:
        """Longitudinal force demand [N]: feed-forward plus PI on the speed error."""
        s, u = state[STATE["s"]], state[STATE["u"]]
        ahead = s + self.tuning.speed_preview * max(u, 0.0)
        target = np.interp(ahead, self.road.s, self.speed)
        accel = np.interp(ahead, self.road.s, self._accel)
        error = target - u
        self.integral += error * dt
        aero = self.vehicle.aero
        drag = 0.5 * aero.air_density * aero.reference_area * aero.drag_coefficient * u * abs(u)
        rolling = vehicle_plant(self.vehicle).tyre.rolling_resistance * self.vehicle.mass.total
        grade = np.interp(s, self.road.s, self.road.surface.grade)
        m = self.vehicle.mass.total
        demand = accel + self.tuning.speed_gain * error + self.tuning.speed_integral * self.integral
        return m * demand + drag + rolling * GRAVITY + m * GRAVITY * grade / np.hypot(1.0, grade)

    def inputs(self, state: np.ndarray, dt: float) -> np.ndarray:
        """Plant input vector (steer, four drive torques, four brake torques)."""
        line = vehicle_plant(self.vehicle).driveline
        force = self.force(state, dt)
        u = max(state[STATE["u"]], 1.0)
        inp = np.zeros(len(INPUT_NAMES))
        inp[0] = self.steer(state)
        if force >= 0.0:
            force = min(force, line.max_power / u)
            shares = (line.drive_share_front, 1.0 - line.drive_share_front)
            offset = 1
        else:
            force = -force
            shares = (line.brake_share_front, 1.0 - line.brake_share_front)
            offset = 5
        for i in range(4):
            inp[offset + i] = 0.5 * shares[i // 2] * force * self._radius[i]
        return inp
