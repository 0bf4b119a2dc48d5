r"""Corner loads from body roll / pitch and the roll-centre height (corner-based paper eq. 17-18).

ISO 8855 axes and signs (roll > 0 lifts the left side, pitch > 0 lowers the
nose). The specific force is rotated by the body pitch and roll relative to
the road:

.. math::
    \tilde a_{\theta x} = a_x\cos\theta + a_z\sin\theta, \quad
    \tilde a_{\theta z} = a_z\cos\theta - a_x\sin\theta, \quad
    F_{zf} = \frac{m}{L}(d_r\tilde a_{\theta z} - h\,\tilde a_{\theta x}), \quad
    F_{zr} = \frac{m}{L}(d_f\tilde a_{\theta z} + h\,\tilde a_{\theta x})

(eq. 17 as printed), and per axle (eq. 18)

.. math::
    \tilde a_{\phi y} = a_y\cos\phi - a_z\sin\phi, \quad
    \tilde a_{\phi z} = a_z\cos\phi + a_y\sin\phi, \\
    F_{iL/R} = \frac{m_i}{T_i}\big[\tilde a_{\phi z}(T_i/2 \mp (h - h_{rc})\sin\phi)
               \mp \tilde a_{\phi y} h\big], \quad m_i = F_{zi}/\tilde a_{\phi z}

Derived rather than copied where the print disagrees with ISO axes or with
itself: the roll rotation's :math:`a_z\sin\phi` sign (the paper's roll is
positive the other way); the lateral shift of the sprung CG in roll uses the
arm above the roll centre, :math:`h - h_{rc}`, where the paper writes
:math:`h_{RC}`; and the equivalent axle mass divides by
:math:`\tilde a_{\phi z}`, not g, so that the two corners of an axle add up to
eq. (17)'s axle load (the printed :math:`F_{zi}/g` counts the vertical
specific force twice). Aerodynamic lift is not in the paper's model.
"""

from __future__ import annotations

import casadi as ca

#: Order of the parameter vector of :func:`corner_load_function`.
CORNER_PARAMETERS = (
    "mass", "lf", "lr", "cg_height", "track_front", "track_rear", "roll_centre_height",
)  # fmt: skip


def corner_loads(acc, roll, pitch, cp):
    """Loads FL, FR, RL, RR from specific force, roll, pitch and parameters ``cp`` (eq. 17-18)."""
    m, lf, lr, h, t_f, t_r, h_rc = (cp[i] for i in range(len(CORNER_PARAMETERS)))
    ax, ay, az = acc[0], acc[1], acc[2]
    a_tx = ax * ca.cos(pitch) + az * ca.sin(pitch)
    a_tz = az * ca.cos(pitch) - ax * ca.sin(pitch)
    wheelbase = lf + lr
    axle = (m / wheelbase * (lr * a_tz - h * a_tx), m / wheelbase * (lf * a_tz + h * a_tx))
    a_py = ay * ca.cos(roll) - az * ca.sin(roll)
    a_pz = az * ca.cos(roll) + ay * ca.sin(roll)
    loads = []
    for load, track in zip(axle, (t_f, t_r)):
        mass = load / a_pz
        shift = (h - h_rc) * ca.sin(roll)
        loads.append(mass / track * (a_pz * (track / 2 - shift) - a_py * h))
        loads.append(mass / track * (a_pz * (track / 2 + shift) + a_py * h))
    return ca.vertcat(*loads)


def corner_load_function(name: str = "corner_loads") -> ca.Function:
    """``name(acc[3], roll, pitch, cp[7]) -> fz[4]`` (eq. 17-18)."""
    acc = ca.SX.sym("acc", 3)
    roll, pitch = ca.SX.sym("roll"), ca.SX.sym("pitch")
    cp = ca.SX.sym("cp", len(CORNER_PARAMETERS))
    return ca.Function(
        name,
        [acc, roll, pitch, cp],
        [corner_loads(acc, roll, pitch, cp)],
        ["acc", "roll", "pitch", "cp"],
        ["fz"],
    )
