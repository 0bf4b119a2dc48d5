r"""Tyre forces from wheel and body dynamics (corner-based paper §III-A/B, eq. 1-16).

Signs derived here (ISO 8855, tyre frame: x along the wheel heading in the road plane,
y to its left; the front road-wheel angle :math:`\delta > 0` steers left), not copied
from the paper's printed equations:

- Wheel spin (eq. 1): :math:`J \dot\omega = T - R F_x - f_r R F_z \tanh(\omega/\omega_s)`
  (:func:`longitudinal_force`), the plant's own wheel equation with the rolling
  resistance named apart (the paper's :math:`\Omega_x`).
- The printed observer (eq. 4-5) needs the spin acceleration :math:`\dot\omega` of eq. 4's
  feed-through and the force error :math:`\tilde F_x = F_x - \hat F_x` of its :math:`k_3`
  term, neither of which is measured. Its implementable form (:func:`observer_matrices`)
  takes :math:`\dot\omega` as the observer's own estimate :math:`\hat a`, driven by the
  spin error :math:`\tilde\omega = \omega - \hat\omega` through eq. 5's integral
  :math:`k_2 \int \tilde\omega\, dt`:

  .. math:: \hat F = \frac{T - J \hat a}{R} - k_1 \tilde\omega, \qquad
            \dot{\hat\omega} = \hat a + \frac{R k_1}{J} \tilde\omega, \qquad
            \dot{\hat a} = \frac{k_2}{J} \tilde\omega

  so the spin error obeys eq. 9 exactly, :math:`J \ddot{\tilde\omega} + R k_1
  \dot{\tilde\omega} + k_2 \tilde\omega = J \dddot\omega`, and the force error is
  :math:`\hat F - F = (J/R)\, \dot{\tilde\omega}`: zero for any constant spin
  acceleration, whatever the torque does (the torque feeds through, as in eq. 4). The
  :math:`k_3` term integrates :math:`\tilde F_x` to remove a constant model error
  :math:`\Omega_x` (a torque or radius scale); online only the sum of the four errors is
  seen, through the body's force balance, and its integral with the torques as regressor
  is a torque-gain state of the lateral filter
  (:mod:`~wheelload.estimators.family.tyres.step`).
- Body forces (eq. 2-3, :func:`body_force_rows`): the tyres' forces in the road plane
  equal the whole-vehicle mass times the specific force in the road frame (the body's
  roll and pitch relative to the road from the travels, eq. 7 and 4-5 of the main paper)
  plus the drag, :math:`S_x = m \check a_x + D`, :math:`S_y = m \check a_y`; with an
  accelerometer's specific force the road's own grade and bank drop out (the paper's
  :math:`\theta_r, \phi_r` correct a kinematic acceleration). Yaw about the sprung CG,

  .. math:: I_z \dot r = l_f (F_{yf} \cos\delta + F_{xf} \sin\delta)
            + \tfrac{t_f}{2} (\bar F_{xf} \cos\delta - \bar F_{yf} \sin\delta)
            - l_r F_{yr} + \tfrac{t_r}{2} \bar F_{xr},

  :math:`\bar F = F_R - F_L`: eq. 3 as printed; the printed output matrix (11) has the
  opposite sign on :math:`\bar F_{yf}`, and its measurement is the yaw acceleration, not
  the rate (here the rate is a filter state and the gyro measures it).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

#: rad/s: brake and rolling-resistance torques fade below this spin (they oppose the rolling
#: direction); the plant's wheels and the estimators' share it.
SPIN_SMOOTHING = 0.5
#: The paper's observer gains (§IV) and the wheel they were set for: k1 [N s/rad],
#: k2 [N m/rad], k3 [1/s]; I_w [kg m^2], R_e [m].
PAPER_GAINS = {"k1": 3.41, "k2": 16.22, "k3": 67.84, "inertia": 1.7, "radius": 0.346}


def spin_direction(spin):
    r""":math:`\tanh(\omega / \omega_s)`: the sign of a wheel's spin, smoothed below
    :data:`SPIN_SMOOTHING` (brake and rolling-resistance torques fade to zero at rest)."""
    return ca.tanh(spin / SPIN_SMOOTHING)


def rolling_resistance_force(fz, spin, coefficient: float):
    r"""Rolling resistance at the contact patch [N]: :math:`f_r F_z \tanh(\omega/\omega_s)`."""
    return coefficient * fz * spin_direction(spin)


def longitudinal_force(torque, spin_rate, fz, spin, *, inertia, radius, coefficient):
    r"""Eq. 1: :math:`F_x = (T - J\dot\omega)/R - f_r F_z \tanh(\omega/\omega_s)` [N]."""
    return (torque - inertia * spin_rate) / radius - rolling_resistance_force(fz, spin, coefficient)


def observer_matrices(
    *, inertia: float, radius: float, k1: float, k2: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""``(A, B, C, D)`` of the spin observer in eq. 4-5's form (module docstring),
    continuous time.

    State :math:`z = (\hat\omega, \hat a)`, input :math:`u = (T, \omega)`, output the
    force :math:`\hat F = C z + D u` before the rolling resistance:

    .. math:: \dot z = \begin{pmatrix} -R k_1/J & 1 \\ -k_2/J & 0 \end{pmatrix} z
              + \begin{pmatrix} 0 & R k_1/J \\ 0 & k_2/J \end{pmatrix} u, \qquad
              \hat F = (k_1, -J/R)\, z + (1/R, -k_1)\, u
    """
    a = np.array([[-radius * k1 / inertia, 1.0], [-k2 / inertia, 0.0]])
    b = np.array([[0.0, radius * k1 / inertia], [0.0, k2 / inertia]])
    return a, b, np.array([k1, -inertia / radius]), np.array([1.0 / radius, -k1])


def observer_gains(*, inertia: float, radius: float, frequency: float, damping: float):
    r"""``(k1, k2)`` placing eq. 9's poles at natural frequency ``frequency`` [Hz] and
    ``damping``: :math:`k_2 / J = \omega_n^2`, :math:`R k_1 / J = 2 \zeta \omega_n`."""
    omega_n = 2.0 * np.pi * frequency
    return 2.0 * damping * omega_n * inertia / radius, omega_n**2 * inertia


def observer_poles(*, k1: float, k2: float, inertia: float, radius: float):
    """``(frequency [Hz], damping)`` of eq. 9 for gains ``k1, k2`` on a wheel: the inverse
    of :func:`observer_gains` (the paper's gains map to another wheel by their poles)."""
    omega_n = float(np.sqrt(k2 / inertia))
    return omega_n / (2.0 * np.pi), radius * k1 / inertia / (2.0 * omega_n)


def body_force_rows(
    steer, fx, *, lf, lr, track_front, track_rear, share_front, inertia_z, cg_shift=(0.0, 0.0)
):
    r"""Rows of :math:`(S_x, S_y, I_z \dot r)` in the lateral state
    :math:`(F_{yf}, F_{yr}, e)` and the part the longitudinal forces ``fx`` (4,) give.

    :math:`e` is the front left/right difference beyond the normal-load split,
    :math:`\bar F_{yf} = s F_{yf} + e` with ``share_front`` :math:`s = s_{fr} - s_{fl}`
    (:func:`tyre_split`, or :func:`load_shares`: the split the paper names as the simple
    alternative; :math:`e` carries what differs).
    Returns ``(H (3, 3), offset (3,))``, the yaw row divided by ``inertia_z`` (yaw
    acceleration). ``cg_shift`` :math:`(\delta x, \delta y)`: the CG moved ahead and left
    of the file's (a payload); the yaw moment about it is
    :math:`M - \delta x \sum B_y + \delta y \sum B_x` with the body-frame sums of rows 1-2.
    """
    c, s = ca.cos(steer), ca.sin(steer)
    fxf, fxr = fx[0] + fx[1], fx[2] + fx[3]
    bar_xf, bar_xr = fx[1] - fx[0], fx[3] - fx[2]
    half_f, half_r = 0.5 * track_front, 0.5 * track_rear
    h = ca.vertcat(
        ca.horzcat(-s, 0.0, 0.0),
        ca.horzcat(c, 1.0, 0.0),
        ca.horzcat(lf * c - half_f * s * share_front, -lr, -half_f * s) / inertia_z,
    )
    offset = ca.vertcat(
        fxf * c + fxr, fxf * s, (lf * fxf * s + half_f * bar_xf * c + half_r * bar_xr) / inertia_z
    )
    dx, dy = cg_shift[0] / inertia_z, cg_shift[1] / inertia_z
    h[2, :] = h[2, :] - dx * h[1, :] + dy * h[0, :]
    offset[2] = offset[2] - dx * offset[1] + dy * offset[0]
    return h, offset


def tyre_split(loads, axle_forces, *, nominal_loads, friction, load_sensitivity, cornering_load):
    r"""Left/right shares (4,) of each axle's lateral force by the tyres' load sensitivity.

    Both tyres of an axle run at about one slip angle. In the linear range their forces
    go as the Magic Formula's cornering stiffness :math:`K_y \propto \sin(2\arctan(F_z /
    (p_{Ky2} F_{z0})))`; at the limit as the peak :math:`D = \mu_y (1 + p_{D2}\, df_z) F_z`.
    The share blends the two by the axle's utilisation :math:`\eta = |F_{y,axle}| /
    (D_L + D_R)` (clipped to [0, 1]): :math:`s_i = (1 - \eta) K_{y,i} / \sum K_y +
    \eta D_i / \sum D`, exact at both ends. ``axle_forces`` (front, rear), ``nominal_loads``
    (front, rear) :math:`F_{z0}`.
    """
    shares = []
    for axle in range(2):
        left, right = ca.fmax(loads[2 * axle], 1.0), ca.fmax(loads[2 * axle + 1], 1.0)
        nominal = nominal_loads[axle]
        k_left, k_right = (ca.sin(2.0 * ca.atan(f / (cornering_load * nominal)))
                           for f in (left, right))  # fmt: skip
        d_left, d_right = (ca.fmax(friction * (1.0 + load_sensitivity * (f - nominal) / nominal)
                                   * f, 1.0) for f in (left, right))  # fmt: skip
        eta = ca.fmin(ca.fabs(axle_forces[axle]) / (d_left + d_right), 1.0)
        for k, d in ((k_left, d_left), (k_right, d_right)):
            shares.append((1.0 - eta) * k / (k_left + k_right) + eta * d / (d_left + d_right))
    return ca.vertcat(*shares)


def load_shares(loads):
    """Left/right shares (4,) of each axle by normal load (the paper's simple split)."""
    fz = [ca.fmax(loads[i], 1.0) for i in range(4)]
    front, rear = fz[0] + fz[1], fz[2] + fz[3]
    return ca.vertcat(fz[0] / front, fz[1] / front, fz[2] / rear, fz[3] / rear)


def wheel_lateral_forces(axles, shares):
    r"""Per-wheel :math:`F_y` (4,) from :math:`(F_{yf}, F_{yr}, e)` and the left/right shares
    (4,, :func:`tyre_split` or :func:`load_shares`): front :math:`F_{y,fl/fr} = s_{fl/fr}
    F_{yf} \mp e/2`, rear :math:`s_{rl/rr} F_{yr}`.

    Linear in the state: returns ``(values (4,), G (4, 3))`` with ``values = G @ axles``.
    """
    g = ca.vertcat(
        ca.horzcat(shares[0], 0.0, -0.5),
        ca.horzcat(shares[1], 0.0, 0.5),
        ca.horzcat(0.0, shares[2], 0.0),
        ca.horzcat(0.0, shares[3], 0.0),
    )
    return ca.mtimes(g, axles), g


def load_share_split(total, loads):
    r"""``total`` (n,) split over the wheels by normal-load share (n, 4): the rigid-body
    baseline's :math:`F_i = S F_{z,i} / \sum F_z`."""
    weights = np.maximum(loads, 0.0)
    return total[:, None] * weights / np.maximum(weights.sum(axis=1, keepdims=True), 1.0)


def wheel_centre_speeds(speed, rate, steer, positions):
    r"""Each wheel centre's speed along its heading [m/s] (4,):
    :math:`v_i = (v_x - r y_i) \cos\delta_i + r x_i \sin\delta_i` (front wheels steered
    by :math:`\delta`, rear 0). The body's lateral speed is taken as 0: on the plant's laps
    and its ABS braking, its true value changes the slip ratios below by < 0.001 rms.
    ``positions``: (x, y) per wheel from the CG [m]."""
    result = []
    for i, (x, y) in enumerate(positions):
        angle = steer if i < 2 else 0.0
        result.append((speed - rate * y) * ca.cos(angle) + rate * x * ca.sin(angle))
    return ca.vertcat(*result)


def slip_ratios(spin, radius, speeds, min_speed: float):
    r"""Each wheel's longitudinal slip ratio (4,): :math:`\kappa_i = (R_{e,i} \omega_i - v_i)
    / \max(|v_i|, v_{min})`, the slip velocity per unit speed (SAE J670, ISO 8855), with
    ``radius`` the effective rolling radius :math:`R_e`
    (:func:`~wheelload.models.vehicle.wheel_geometry.rolling_radius`: with a fixed radius
    the load's change of :math:`R_e` reads as slip) and ``speeds`` :func:`wheel_centre_speeds`;
    ``min_speed`` keeps it finite at rest. A stable wheel's slip follows its force,
    :math:`\kappa \approx F_x / C_\kappa`; past the force peak it runs away (locks or spins).
    """
    return (radius * spin - speeds) / ca.fmax(ca.fabs(speeds), min_speed)
