r"""Input-dependent measurement noise of the filter's update rows (white-noise densities).

The suspension pseudo-measurement's error grows with the damper velocity
(the damper map's departure from the fitted slopes) and with the hub's
motion relative to the body (unsprung dynamics, wheel hop); the equilibrium
rows' error with the accelerations they are built from (the body's inertia
the quasi-static equilibrium, Siegloff & Choi eq. 14-16, leaves out). Per
sample, with the log's nominal interval :math:`\Delta t`:

.. math::

    R_{s,i} &= \big(r_s + r_{sv}\,v_i^2 + r_{sh}\,h_i\,(a_{hub,i} - a_z)^2\big) / \Delta t \\
    R_{c,j} &= \big(r_{c,j} + r_{ca,j}\,e_j^2\big) / \Delta t,
    \quad e = (a_z - g,\; a_x,\; a_y)

for the vertical, pitch and roll rows; :math:`h_i` is 1 where corner i's hub
accelerometer is logged (else the term is off). With every
:math:`r_{sv}, r_{sh}, r_{ca}` zero this is the constant
:math:`R_s = r_s/\Delta t\,I`, :math:`R_c = \mathrm{diag}(r_c)/\Delta t` of
the paper (eq. 20-25), to the bit.

Example
-------
>>> R_s, R_c = measurement_noise_function()(u, u_valid, densities, 0.01)
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.conventions import GRAVITY  # the vertical row's reference specific force
from wheelload.models.inputs import (
    HUB_ACCELERATION,
    INPUTS,
    SPECIFIC_FORCE,
    TRAVEL_RATE,
    input_index,
)

#: The constant densities (the paper's): r_s, r_c vertical, pitch, roll.
BASE_DENSITIES = (
    "suspension_noise_density",
    "constraint_noise_vertical",
    "constraint_noise_pitch",
    "constraint_noise_roll",
)
#: The input-dependent densities (vehicle file ``[filter]``, optional, default 0).
INPUT_DENSITIES = (
    "suspension_noise_rate_density",  # r_sv [N^2 s / (m/s)^2], per v_i^2
    "suspension_noise_hub_density",  # r_sh [N^2 s / (m/s^2)^2], per (a_hub,i - a_z)^2
    "constraint_noise_vertical_acceleration",  # r_ca,1 [N^2 s / (m/s^2)^2], per (a_z - g)^2
    "constraint_noise_pitch_acceleration",  # r_ca,2 [N^2 m^2 s / (m/s^2)^2], per a_x^2
    "constraint_noise_roll_acceleration",  # r_ca,3 [N^2 m^2 s / (m/s^2)^2], per a_y^2
)
#: Order of the ``densities`` input of :func:`measurement_noise_function`.
DENSITIES = BASE_DENSITIES + INPUT_DENSITIES
NAME = "measurement_noise"

_RATE = input_index(TRAVEL_RATE)
_HUB = input_index(HUB_ACCELERATION)
_AX, _AY, _AZ = input_index(SPECIFIC_FORCE)


def measurement_noise(u, u_valid, densities, dt_nominal):
    """``(R_s[4], R_c[3])`` expressions; ``u`` finite (invalid entries already zero)."""
    r = {name: densities[k] for k, name in enumerate(DENSITIES)}
    az = u[_AZ]
    suspension = []
    for i in range(4):
        relative = u[_HUB[i]] - az
        suspension.append(
            r["suspension_noise_density"]
            + r["suspension_noise_rate_density"] * u[_RATE[i]] ** 2
            + r["suspension_noise_hub_density"] * u_valid[_HUB[i]] * relative**2
        )
    accelerations = (az - GRAVITY, u[_AX], u[_AY])
    rows = ("vertical", "pitch", "roll")
    constraint = [
        r[f"constraint_noise_{row}"] + r[f"constraint_noise_{row}_acceleration"] * a**2
        for row, a in zip(rows, accelerations, strict=True)
    ]
    return ca.vertcat(*suspension) / dt_nominal, ca.vertcat(*constraint) / dt_nominal


def measurement_noise_function(name: str = NAME) -> ca.Function:
    r"""``name(u, u_valid, densities, dt_nominal) -> (R_s[4], R_c[3])`` (module equations).

    ``densities`` in :data:`DENSITIES` order; ``u`` in ``INPUTS`` order with
    invalid entries zero and ``u_valid`` 1 where an input is valid.
    """
    u = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    densities = ca.SX.sym("densities", len(DENSITIES))
    dt = ca.SX.sym("dt_nominal")
    R_s, R_c = measurement_noise(u, valid, densities, dt)
    return ca.Function(
        name, [u, valid, densities, dt], [R_s, R_c],
        ["u", "u_valid", "densities", "dt_nominal"], ["R_s", "R_c"],
    )  # fmt: skip
