r"""Quarter-car corner model for the per-corner observers (Siegloff & Choi §IV-B, methods E, F).

Per corner, with compression :math:`d` (> 0 in bump, so :math:`z_u - z_s = d`
+ const), suspension load :math:`z` of the suspension model (eq. 9: static
load, spring, damper and anti-roll bar, i.e. the force through the
suspension plus the unsprung weight), tyre normal load :math:`F`, unsprung
mass :math:`m_u` and kinematic vertical acceleration of the body corner
:math:`a_s` (up > 0):

.. math::
    m_u \ddot z_u = F - (z - m_u g) - m_u g = F - z, \qquad
    \ddot d = \ddot z_u - \ddot z_s = \frac{F - z}{m_u} - a_s

The body corner's acceleration is reconstructed from the body IMU at the
corner's position :math:`(x_i, y_i)` relative to the IMU (rigid body, ISO
8855: pitch rate > 0 nose down, roll rate > 0 right side down):

.. math:: a_{s,i} = a_z - g - x_i \dot\omega_y + y_i \dot\omega_x
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.vehicle import GRAVITY


def compression_acceleration(F, z, a_s, m_u):
    r""":math:`\ddot d = (F - z)/m_u - a_s` (module docstring)."""
    return (F - z) / m_u - a_s


def corner_acceleration(az, omega_dot, x, y):
    r"""Kinematic vertical acceleration of a body point :math:`(x, y)` from the IMU [m/s^2]."""
    return az - GRAVITY - x * omega_dot[1] + y * omega_dot[0]


def quarter_car_function(name: str = "quarter_car") -> ca.Function:
    """``name(F, z, a_s, m_u) -> d_ddot``: the corner's compression acceleration."""
    F, z, a_s, m_u = (ca.SX.sym(s) for s in ("F", "z", "a_s", "m_u"))
    return ca.Function(
        name,
        [F, z, a_s, m_u],
        [compression_acceleration(F, z, a_s, m_u)],
        ["F", "z", "a_s", "m_u"],
        ["d_ddot"],
    )


def corner_acceleration_function(name: str = "corner_acceleration") -> ca.Function:
    """``name(az, omega_dot[3], x, y) -> a_s``: the body corner's vertical acceleration."""
    az, x, y = ca.SX.sym("az"), ca.SX.sym("x"), ca.SX.sym("y")
    omega_dot = ca.SX.sym("omega_dot", 3)
    return ca.Function(
        name,
        [az, omega_dot, x, y],
        [corner_acceleration(az, omega_dot, x, y)],
        ["az", "omega_dot", "x", "y"],
        ["a_s"],
    )
