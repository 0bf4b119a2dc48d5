r"""Vertical-load model of the road-angle paper (Jiang et al., eq. 6-11, 13-15) in ISO axes.

State (eq. 13):
:math:`x = [\phi, \dot\phi, \theta, \dot\theta, F_{FL}, F_{FR}, F_{RL}, F_{RR},
a_{xr}, \dot a_{xr}, a_{yr}, \dot a_{yr}, a_{zr}, \dot a_{zr}]`, with
:math:`\phi, \theta` the body roll and pitch relative to the road (eq. 7) and
:math:`a_r` the specific force in the road frame ("equivalent accelerations",
eq. 4-5).

Roll and pitch dynamics (eq. 6), the pitch sign derived for ISO axes (a
forward acceleration lifts the nose, :math:`\theta < 0`; the paper prints
:math:`+m h_s a_x`):

.. math::
    I_\phi \ddot\phi = -C_\phi \dot\phi - K_\phi \phi + m_s h_s a_{yr}, \quad
    I_\theta \ddot\theta = -C_\theta \dot\theta - K_\theta \theta - m_s h_s a_{xr}

with :math:`I` about the roll / pitch axis (CG inertia plus :math:`m_s h_s^2`).
The accelerations are constant-velocity random walks (:math:`\ddot a = 0`, eq. 15's
assumption). The paper's load equations (8)-(11) are not printed in full;
they are rebuilt from its text: the vertical force shared by the static
lever arms, and the load transfer "caused by the torque of the suspension
systems" (eq. 10), :math:`M_\phi = K_\phi\phi + C_\phi\dot\phi` split between
the axles by their roll stiffness, :math:`M_\theta = K_\theta\theta +
C_\theta\dot\theta` over the wheelbase:

.. math::
    F_{iL/R} = \tfrac12 m a_{zr} \frac{l_{\bar i}}{L} \pm_i \frac{M_\theta}{2L}
               \mp \frac{s_i M_\phi}{T_i}

(front +, rear - for pitch; right +, left - for roll). The load states evolve
as the time derivative of this model along the dynamics (eq. 15 is not
printed either), so the system stays linear.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from wheelload.models.body_attitude import roll_pitch_stiffness
from wheelload.models.mass_properties import vehicle_mass_centre
from wheelload.models.vehicle.description import Vehicle

STATE_NAMES = (
    "roll", "roll_rate", "pitch", "pitch_rate", "fz_fl", "fz_fr", "fz_rl", "fz_rr",
    "ax_r", "ax_r_rate", "ay_r", "ay_r_rate", "az_r", "az_r_rate",
)  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class BodyInertia:
    """Sprung-body inertia about its CG [kg m^2] and the roll / pitch axis height [m].

    :meth:`from_vehicle` takes the roll and pitch inertia from the vehicle file's
    ``mass.inertia`` (Ixx, Iyy); the axis on the ground by default, so the arm is the CG
    height.
    """

    roll: float
    pitch: float
    axis_height: float = 0.0

    @classmethod
    def from_vehicle(cls, vehicle: Vehicle, *, axis_height: float = 0.0) -> BodyInertia:
        """The vehicle file's sprung-body Ixx and Iyy about the CG."""
        roll, pitch, _ = vehicle.mass.inertia
        return cls(roll=float(roll), pitch=float(pitch), axis_height=axis_height)

    def __post_init__(self) -> None:
        if not (self.roll > 0 and self.pitch > 0 and self.axis_height >= 0):
            raise ValueError(
                "body inertia must be > 0 and the axis height >= 0, "
                f"got {self.roll}, {self.pitch}, {self.axis_height}"
            )


def road_angle_model(vehicle: Vehicle, inertia: BodyInertia) -> ca.Function:
    """``road_angle_model(x[14]) -> (xdot[14], loads[4])`` (see module docstring)."""
    x = ca.SX.sym("x", len(STATE_NAMES))
    roll, roll_rate, pitch, pitch_rate = x[0], x[1], x[2], x[3]
    ax, ax_dot, ay, ay_dot, az, az_dot = x[8], x[9], x[10], x[11], x[12], x[13]
    k = roll_pitch_stiffness(vehicle)
    centre = vehicle_mass_centre(vehicle)
    g = vehicle.geometry
    m, m_s = vehicle.mass.total, vehicle.mass.sprung
    arm = g.cg_height - inertia.axis_height
    i_roll = inertia.roll + m_s * arm**2
    i_pitch = inertia.pitch + m_s * arm**2
    roll_acc = (-k.roll_damping * roll_rate - k.roll * roll + m_s * arm * ay) / i_roll
    pitch_acc = (-k.pitch_damping * pitch_rate - k.pitch * pitch - m_s * arm * ax) / i_pitch

    def loads_of(roll, roll_rate, pitch, pitch_rate, az):
        wheelbase = centre.lf + centre.lr
        moment_roll = k.roll * roll + k.roll_damping * roll_rate
        moment_pitch = k.pitch * pitch + k.pitch_damping * pitch_rate
        front = 0.5 * m * az * centre.lr / wheelbase + 0.5 * moment_pitch / wheelbase
        rear = 0.5 * m * az * centre.lf / wheelbase - 0.5 * moment_pitch / wheelbase
        lateral_front = k.roll_share_front * moment_roll / g.track_front
        lateral_rear = (1 - k.roll_share_front) * moment_roll / g.track_rear
        return ca.vertcat(
            front - lateral_front, front + lateral_front, rear - lateral_rear, rear + lateral_rear
        )

    loads = loads_of(roll, roll_rate, pitch, pitch_rate, az)
    # d/dt of the load model along the dynamics: linear in x.
    rates = ca.vertcat(roll_rate, roll_acc, pitch_rate, pitch_acc, az_dot)
    kinematic = ca.vertcat(roll, roll_rate, pitch, pitch_rate, az)
    load_rates = ca.mtimes(ca.jacobian(loads, kinematic), rates)
    xdot = ca.vertcat(
        roll_rate, roll_acc, pitch_rate, pitch_acc, load_rates,
        ax_dot, 0, ay_dot, 0, az_dot, 0,
    )  # fmt: skip
    return ca.Function("road_angle_model", [x], [xdot, loads], ["x"], ["xdot", "loads"])
