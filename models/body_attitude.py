r"""Body attitude relative to the road, and body-frame kinematics of the corners.

ISO 8855 axes (x forward, y left, z up), roll :math:`\phi > 0` lifts the left
side, pitch :math:`\theta > 0` lowers the nose; travel ``d > 0`` in compression.

- :func:`attitude_from_travel` (road-angle paper eq. 7): body roll and pitch
  relative to the road plane from the four travels,

  .. math:: \phi = \tfrac12\Big(\frac{d_{FR} - d_{FL}}{T_f} + \frac{d_{RR} - d_{RL}}{T_r}\Big),
            \quad \theta = \frac{d_{FL} + d_{FR} - d_{RL} - d_{RR}}{2 L}

  (the paper prints the roll difference the other way round: with
  compression positive, a compressed left side is a left side *down*, which is
  negative roll); :func:`body_attitude_function` is it as a CasADi Function of
  the parameter vector.
- :func:`road_frame` (eq. 4-5): specific force rotated from the body into the
  road frame, :math:`a_r = R_y(\theta) R_x(\phi) a_m` (the paper's labels of
  the two matrices are swapped: its :math:`R_\theta` is a rotation about x).
- :func:`corner_vertical_acceleration`: sprung-mass vertical acceleration at
  each corner without gravity, :math:`a_{s,i} = a_z - g + \dot\omega_x y_i -
  \dot\omega_y x_i` (rigid body, centripetal terms left out), positions
  relative to the IMU.
- :func:`roll_pitch_stiffness`: suspension roll and pitch stiffness and
  damping from the springs, dampers and anti-roll bars of the vehicle file.
- :func:`attitude_from_equilibrium`: the suspension's quasi-static roll and
  pitch under the measured specific force (no travel sensor needed),

  .. math:: \phi = \frac{m_s (h_s - h_{rc}) f_y}{K_\phi}, \quad
            \theta = -\frac{m_s h_s (1 - a) f_x}{K_\theta}

  and :func:`attitude_travel`, the four travels of a body roll and pitch.
- :func:`lateral_mismatch`: the lateral specific force the path's curvature does not
  explain, :math:`a_y - v_x \omega_z` (the body's lateral velocity rate
  :math:`\dot v_y` plus the gravity of bank and roll; a lag or bias of the ``ay`` channel
  shows in it too).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.parameters import ModelParameters
from wheelload.models.vehicle.description import Vehicle
from wheelload.models.vehicle.wheel_geometry import wheel_centres


def roll_axis_height(p: ModelParameters):
    r"""Height of the roll axis under the CG: :math:`h_{rc} = (l_r h_{rc,f} + l_f h_{rc,r}) / l`."""
    return (p.lr * p.roll_centre_front + p.lf * p.roll_centre_rear) / (p.lf + p.lr)


def attitude_from_travel(d, track_front, track_rear, wheelbase):
    """Body roll and pitch relative to the road [rad] from travels FL, FR, RL, RR (eq. 7)."""
    roll = 0.5 * ((d[1] - d[0]) / track_front + (d[3] - d[2]) / track_rear)
    pitch = (d[0] + d[1] - d[2] - d[3]) / (2.0 * wheelbase)
    return roll, pitch


def body_attitude_function(name: str = "body_attitude") -> ca.Function:
    """``name(d[4], p) -> (pitch, roll)``: :func:`attitude_from_travel` with the parameters'
    tracks and wheelbase :math:`l_f + l_r` (whole-vehicle CG, as the equilibrium)."""
    d = ca.SX.sym("d", 4)
    p_vector, p = ModelParameters.symbolic()
    roll, pitch = attitude_from_travel(d, p.track_front, p.track_rear, p.lf + p.lr)
    return ca.Function(name, [d, p_vector], [pitch, roll], ["d", "p"], ["pitch", "roll"])


def road_frame(acc, roll, pitch, sine=None, cosine=None):
    r"""Specific force in the road frame, :math:`R_y(\theta) R_x(\phi) a` (eq. 4-5).

    ``sine`` and ``cosine`` (default ``ca.sin``, ``ca.cos``) may be replaced by
    polynomials (the model terms use their Taylor polynomials so that a generated
    step has no trigonometry).
    """
    sine, cosine = sine or ca.sin, cosine or ca.cos
    c_r, s_r, c_p, s_p = cosine(roll), sine(roll), cosine(pitch), sine(pitch)
    rx = ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c_r, -s_r), ca.horzcat(0, s_r, c_r))
    ry = ca.vertcat(ca.horzcat(c_p, 0, s_p), ca.horzcat(0, 1, 0), ca.horzcat(-s_p, 0, c_p))
    return ca.mtimes(ry, ca.mtimes(rx, acc))


def attitude_function(vehicle: Vehicle, name: str = "body_attitude") -> ca.Function:
    """``name(d[4], acc[3]) -> (roll, pitch, acc_road[3])``: eq. 7 then eq. 4-5."""
    d = ca.SX.sym("d", 4)
    acc = ca.SX.sym("acc", 3)
    g = vehicle.geometry
    roll, pitch = attitude_from_travel(d, g.track_front, g.track_rear, g.wheelbase)
    return ca.Function(
        name,
        [d, acc],
        [roll, pitch, road_frame(acc, roll, pitch)],
        ["d", "acc"],
        ["roll", "pitch", "acc_road"],
    )


def corner_positions(vehicle: Vehicle) -> np.ndarray:
    """Wheel centres (x, y) relative to the IMU [m], rows FL, FR, RL, RR."""
    g = vehicle.geometry
    x_imu, y_imu = g.imu_position[0], g.imu_position[1]
    return np.array([(x - x_imu, y - y_imu) for x, y in wheel_centres(g)])


def corner_vertical_acceleration(az, roll_acc, pitch_acc, positions):
    r""":math:`a_{s,i} = a_z - g + \dot\omega_x y_i - \dot\omega_y x_i` at the four corners.

    ``positions``: rows (x, y), an array or a sequence of pairs (numbers or symbols).
    """
    rows = positions.tolist() if isinstance(positions, np.ndarray) else positions
    return ca.vertcat(*[az - GRAVITY + roll_acc * y - pitch_acc * x for x, y in rows])


@dataclass(frozen=True, kw_only=True)
class RollPitchStiffness:
    """Suspension roll / pitch stiffness [N m/rad] and damping [N m s/rad] of the body."""

    roll: float
    roll_damping: float
    roll_share_front: float  # front axle's part of the roll stiffness
    pitch: float
    pitch_damping: float


def lateral_mismatch(ay, vx, wz):
    r""":math:`a_y - v_x \omega_z`: the lateral specific force minus the centripetal
    acceleration of the path (rigid body in the plane, ISO 8855: a left turn has
    :math:`\omega_z > 0`, :math:`a_y > 0`); :math:`\dot v_y` plus bank and roll gravity
    and any lag or bias of ``ay``."""
    return ay - vx * wz


def roll_pitch_stiffness(vehicle: Vehicle) -> RollPitchStiffness:
    r"""Body roll and pitch rates of the wheel-rate springs, dampers and bars.

    Per axle :math:`K_\phi = (k/2 + \gamma k_{arb}) T^2` (left and right travel
    :math:`\mp T\phi/2`), damping :math:`\bar c T^2 / 2` with :math:`\bar c`
    the mean of push and pull rates; pitch about the sprung CG
    :math:`K_\theta = 2 (k_f l_f^2 + k_r l_r^2)`.
    """
    g, s = vehicle.geometry, vehicle.suspension
    axles = ((s.front, g.track_front, g.lf), (s.rear, g.track_rear, g.lr))
    roll = [axle_roll_stiffness(a.spring_rate, a.arb_rate, a.arb_ratio, t) for a, t, _ in axles]
    damping = [0.5 * (a.damper_push + a.damper_pull) for a, _, _ in axles]
    return RollPitchStiffness(
        roll=sum(roll),
        roll_damping=sum(c * t**2 / 2 for c, (_, t, _) in zip(damping, axles)),
        roll_share_front=roll[0] / sum(roll),
        pitch=sum(2 * a.spring_rate * arm**2 for a, _, arm in axles),
        pitch_damping=sum(2 * c * arm**2 for c, (_, _, arm) in zip(damping, axles)),
    )


def axle_roll_stiffness(spring, arb_rate, arb_ratio, track):
    r"""Roll stiffness of one axle [N m/rad], :math:`K_{\phi,a} = (k/2 + \gamma k_{arb}) T^2`
    (left and right travel :math:`\mp T\phi/2`, bar of eq. 6-8)."""
    return (spring / 2 + arb_ratio * arb_rate) * track**2


def attitude_from_equilibrium(f, p: ModelParameters):
    r"""Quasi-static suspension roll and pitch [rad] under the CG specific force ``f`` (body axes).

    .. math:: \phi = \frac{m_s (h_s - h_{rc}) f_y}{K_{\phi,f} + K_{\phi,r}}, \quad
        \theta = -\frac{m_s h_s (1 - a) f_x}{2 (k_f l_f^2 + k_r l_r^2)}, \quad
        a = \frac{l_f a_f + l_r a_r}{l_f + l_r}

    The sprung mass rolls about the roll axis (:func:`roll_axis_height`) and pitches
    about its CG, the links carrying the anti-pitch share :math:`a` (anti-dive and
    rear anti-lift when :math:`f_x < 0`, anti-lift and anti-squat otherwise, as
    :func:`~wheelload.models.suspension.parts.link_loads`). The body-axis specific
    force already holds the gravity moment of the displaced CG (:math:`f_y = \tilde
    f_y + g\phi`, :math:`f_x = \tilde f_x - g\theta` to first order), so no
    :math:`K - m_s g h` correction appears. ISO 8855 signs: a left turn (:math:`f_y >
    0`) rolls the body to the right (:math:`\phi > 0`), braking (:math:`f_x < 0`)
    pitches the nose down (:math:`\theta > 0`). A pure function of the sample: no state.
    """
    (k_f, arb_f, ratio_f), (k_r, arb_r, ratio_r) = p.axles("spring", "arb_rate", "arb_ratio")
    roll_stiffness = axle_roll_stiffness(k_f, arb_f, ratio_f, p.track_front) + (
        axle_roll_stiffness(k_r, arb_r, ratio_r, p.track_rear)
    )
    pitch_stiffness = 2 * (k_f * p.lf**2 + k_r * p.lr**2)
    braking = f[0] < 0
    front = ca.if_else(braking, p.anti_brake_front, p.anti_drive_front)
    rear = ca.if_else(braking, p.anti_brake_rear, p.anti_drive_rear)
    anti = (p.lf * front + p.lr * rear) / (p.lf + p.lr)
    h_s = p.sprung_cg_height
    roll = p.sprung_mass * (h_s - roll_axis_height(p)) * f[1] / roll_stiffness
    pitch = -p.sprung_mass * h_s * (1 - anti) * f[0] / pitch_stiffness
    return roll, pitch


def attitude_travel(roll, pitch, p: ModelParameters) -> ca.SX:
    r"""Travels FL, FR, RL, RR [m] of a body roll and pitch about the CG (inverse of eq. 7).

    .. math:: d = \big(l_f\theta - \tfrac{T_f}{2}\phi,\; l_f\theta + \tfrac{T_f}{2}\phi,\;
        -l_r\theta - \tfrac{T_r}{2}\phi,\; -l_r\theta + \tfrac{T_r}{2}\phi\big)
    """
    half_f, half_r = 0.5 * p.track_front * roll, 0.5 * p.track_rear * roll
    front, rear = p.lf * pitch, -p.lr * pitch
    return ca.vertcat(front - half_f, front + half_f, rear - half_r, rear + half_r)
