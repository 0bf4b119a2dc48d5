r"""Closed-loop driver: preview (pure-pursuit) steering and a speed controller.

Steering aims at the target point a preview distance :math:`L_p = \max(L_0,
T_p u)` ahead on the target path, located on the centre line that the plant
drives on, :math:`\psi' = \kappa(s)` integrated from the road's curvature
(:func:`~wheelload.studies.drive.roads.integrate_centre_line`). The road's own
``x, y, heading`` are the source polyline of a track, straight between
vertices 5 m apart: its heading steps at every vertex (by up to 8 deg in a
hairpin), and steering on it jerked the wheel at :math:`u / 5` m (2.7 Hz at
13 m/s) into a limit cycle near the grip limit; with :math:`e` its lateral offset and
:math:`\ell` its distance in the vehicle frame, the demanded path curvature is
:math:`c = 2 e / \ell^2` and the road-wheel angle

.. math:: \delta = c L + K_{us} (u^2 c + g \sin\beta) + k_r (u c - r) + k_I \int e_n\,dt

with the linear-bicycle understeer gradient :math:`K_{us} = (m / L)(l_r / C_f -
l_f / C_r)` applied to the lateral tyre force per unit mass, which on a road
of bank angle :math:`\beta` also carries the downhill pull of gravity (the
steady steer of straight running across a slope). The yaw-rate term damps
the yaw mode, which pure pursuit alone leaves underdamped at 45-60 m/s when
braking unloads the rear axle (it let the car spin on Hockenheim's kink
before the hairpin); the path-error integral is off by default. The angle is rate-limited to
``steer_rate``, a quick human or robot driver (the fastest steering on the
Hockenheim lap is 17 deg/s at the road wheel, under half the limit). (Aiming
along the course, heading plus sideslip, was tried and destabilises the loop
under braking.)

Speed: :math:`F = m (a_{ref} + k_p (v_{ref} - u) + k_i \int (v_{ref} - u))`
plus drag, rolling resistance and grade, limited to the friction ellipse
:math:`|F| \le m \mu g \sqrt{1 - (a_y / \mu g)^2}` with the path's
:math:`a_y = u^2 \kappa` (the measured :math:`r u` swings in yaw transients and
then withholds the braking the car needs) and :math:`\mu` a share of the tyres' cornering friction
(:func:`~wheelload.studies.drive.speed_profile.cornering_friction`); drive is eased
out as the path error grows past ``ease_error``. Drive torque is
power-limited and split by ``drive_share_front``. Brake force is shared in
proportion to the quasi-static axle loads :math:`(l_r + h a_x / g) / L` (what
electronic brake-force distribution does); a fixed front bias over-brakes the
rear above :math:`a_x \approx 0.9 g` and locks it. The longitudinal
force is rate-limited to ``force_rate``. The torques are requests: ABS and
traction control act on them inside the plant chunk at the internal rate
(:mod:`wheelload.models.plant.slip_control`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.plant.dynamics import INPUT_NAMES, STATE, corners, vehicle_plant
from wheelload.models.vehicle.description import Vehicle
from wheelload.studies.drive.roads import Road, integrate_centre_line
from wheelload.studies.drive.speed_profile import cornering_friction


@dataclass(frozen=True, kw_only=True)
class DriverTuning:
    preview_time: float = 0.35  # s
    preview_min: float = 6.0  # m
    speed_gain: float = 1.5  # 1/s
    speed_integral: float = 0.3  # 1/s^2
    speed_preview: float = 0.3  # s, the speed target is read this far ahead
    max_steer: float = 0.6  # rad, road-wheel angle
    steer_rate: float = 0.7  # rad/s, road wheel: 600 deg/s at the hand wheel over a 15:1 ratio
    path_integral: float = 0.0  # rad/(m s), k_I on the path error
    yaw_damping: float = 0.1  # s, k_r on the yaw-rate error u c - r
    friction_use: float = 0.9  # -, share of the cornering friction the speed controller uses
    ease_error: float = 0.5  # m, path error from which drive is eased out ...
    ease_span: float = 1.0  # m, ... reaching zero drive this much further
    force_rate: float = 4.0  # g/s, rate limit of the longitudinal force (pedal speed)
    # The friction the grip limit assumes; None: the tyres' own (cornering_friction). A
    # value above the road's makes the driver demand beyond the grip (dry-road habits on
    # snow): ABS and traction control then hold the wheels.
    assumed_friction: float | None = None


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
    hold: float = 0.0  # s, target speed zero until then (a stop before driving off)
    time: float = 0.0  # s, advanced by each call of inputs()
    integral: float = 0.0
    path_integral: float = 0.0
    last_force: float | None = None
    last_steer: float | None = None

    def __post_init__(self) -> None:
        self._understeer = understeer_gradient(self.vehicle)
        self._accel = np.gradient(0.5 * self.speed**2, self.road.s)
        g = self.vehicle.geometry
        self._length = g.lf + g.lr
        self._radius = [c.radius for c in corners(self.vehicle)]
        assumed = self.tuning.assumed_friction
        friction = cornering_friction(self.vehicle) if assumed is None else assumed
        self._friction = self.tuning.friction_use * friction
        # The plant's own centre line: the integral of the curvature it drives on.
        self._line = integrate_centre_line(self.road.s, self.road.surface.curvature)

    def _point(self, s: float, offset: float):
        grid = self.road.s
        x, y, heading = (np.interp(s, grid, column) for column in self._line)
        return x - offset * np.sin(heading), y + offset * np.cos(heading), heading

    def steer(self, state: np.ndarray, dt: float) -> float:
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
        error = np.interp(s, self.road.s, self.road.target) - n
        self.path_integral += error * dt
        bank = np.interp(s, self.road.s, self.road.surface.bank)
        downhill = GRAVITY * bank / np.hypot(1.0, bank)  # lateral tyre force per mass on a bank
        angle = (
            curvature * self._length
            + self._understeer * (u * u * curvature + downhill)
            + self.tuning.path_integral * self.path_integral
            + self.tuning.yaw_damping * (u * curvature - state[STATE["r"]])
        )
        angle = float(np.clip(angle, -self.tuning.max_steer, self.tuning.max_steer))
        if self.last_steer is not None:
            step = self.tuning.steer_rate * dt
            angle = float(np.clip(angle, self.last_steer - step, self.last_steer + step))
        self.last_steer = angle
        return angle

    def force(self, state: np.ndarray, dt: float) -> float:
        """Longitudinal force demand [N]: feed-forward plus PI on the speed error, grip-limited."""
        s, u = state[STATE["s"]], state[STATE["u"]]
        ahead = s + self.tuning.speed_preview * max(u, 0.0)
        target = np.interp(ahead, self.road.s, self.speed)
        accel = np.interp(ahead, self.road.s, self._accel)
        if self.time < self.hold:
            target, accel = 0.0, 0.0
        error = target - u
        aero = self.vehicle.aero
        drag = 0.5 * aero.air_density * aero.reference_area * aero.drag_coefficient * u * abs(u)
        rolling = vehicle_plant(self.vehicle).tyre.rolling_resistance * self.vehicle.mass.total
        grade = np.interp(s, self.road.s, self.road.surface.grade)
        m = self.vehicle.mass.total
        demand = accel + self.tuning.speed_gain * error + self.tuning.speed_integral * self.integral
        force = m * demand + drag + rolling * GRAVITY + m * GRAVITY * grade / np.hypot(1.0, grade)
        mu_g = self._friction * GRAVITY
        curvature = np.interp(s, self.road.s, self.road.surface.curvature)
        lateral = min(u * u * abs(curvature) / mu_g, 1.0)
        limit = m * mu_g * np.sqrt(1.0 - lateral * lateral)
        path_error = abs(np.interp(s, self.road.s, self.road.target) - state[STATE["n"]])
        ease = np.clip(1.0 - (path_error - self.tuning.ease_error) / self.tuning.ease_span, 0, 1)
        bounded = float(np.clip(force, -limit, limit * ease))
        if self.last_force is not None:
            step = self.tuning.force_rate * m * GRAVITY * dt
            bounded = float(np.clip(bounded, self.last_force - step, self.last_force + step))
        self.last_force = bounded
        if bounded == force:  # anti-windup: integrate only while unsaturated
            self.integral += error * dt
        return bounded

    def inputs(self, state: np.ndarray, dt: float) -> np.ndarray:
        """Input request (steer, four drive and four brake torques), before slip control."""
        line = vehicle_plant(self.vehicle).driveline
        force = self.force(state, dt)
        self.time += dt
        u = max(state[STATE["u"]], 1.0)
        inp = np.zeros(len(INPUT_NAMES))
        inp[0] = self.steer(state, dt)
        if force >= 0.0:
            force = min(force, line.max_power / u)
            front = line.drive_share_front
            offset = 1
        else:
            force = -force
            g = self.vehicle.geometry
            front = (g.lr + g.cg_height * force / (self.vehicle.mass.total * GRAVITY)) / (
                self._length
            )
            offset = 5
        shares = (front, 1.0 - front)
        torque = np.array([0.5 * shares[i // 2] * force * self._radius[i] for i in range(4)])
        inp[offset : offset + 4] = torque
        return inp
