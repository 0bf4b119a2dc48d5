r"""The model parameters of a vehicle carrying a payload its file does not know.

A payload of mass :math:`\Delta m` with first moments
:math:`S = \Delta m\,(x_p, y_p, z_p)` about the file's whole-vehicle CG (ISO 8855 body
axes: x forward, y left, z up) is rigidly part of the sprung body. With
:math:`M = m + \Delta m` the loaded vehicle's CG moves by :math:`\delta = S / M`:

.. math::
    m' = M, \quad l_f' = l_f - \delta_x, \quad l_r' = l_r + \delta_x, \quad
    y_c' = y_c + \delta_y, \quad h' = h + \delta_z, \\
    m_s' = m_s + \Delta m, \quad m_s' h_s' = m_s h_s + \Delta m\, h + S_z,

and the points given relative to the CG (aerodynamic centre) or the sprung CG (IMU)
shift with it. The payload's own inertia about its centre is neglected and the body's
inertia is kept (a 150 kg payload 0.5 m from the CG adds about 7 % to
:math:`I_{xx}`); the wheel rates, the static loads of the reference state and every
other parameter are the file's. Every row that uses mass or CG (equilibrium, the
suspension's link loads, the load limit) thus sees the loaded car, while the
suspension's offsets stay the reference state's: travel is measured from it, so the
springs see the payload (:mod:`wheelload.estimators.kf.payload` estimates it online).

Example
-------
>>> loaded = loaded_parameters(ModelParameters.from_vehicle(vehicle), [150, 0, 0, 45])
"""

from __future__ import annotations

import dataclasses

import casadi as ca

from wheelload.models.parameters import ModelParameters

#: The payload states: mass [kg] and first moments about the file's CG [kg m].
PAYLOAD_STATES = ("mass", "moment_x", "moment_y", "moment_z")
#: The loaded vehicle's mass properties reported beside the loads: total mass [kg], CG
#: ahead of and left of the file's CG [m], CG height above ground [m].
MASS_PROPERTIES = ("mass", "cg_x", "cg_y", "cg_height")


def loaded_parameters(p: ModelParameters, payload) -> ModelParameters:
    """``p`` with the payload ``[mass, moment_x, moment_y, moment_z]`` on board (above)."""
    added, moment_x, moment_y, moment_z = (payload[i] for i in range(4))
    total = p.mass + added
    dx, dy, dz = moment_x / total, moment_y / total, moment_z / total
    sprung = p.sprung_mass + added
    # Written as increments, so that no payload gives the file's numbers to the bit.
    sprung_dz = (added * (p.cg_height - p.sprung_cg_height) + moment_z) / sprung
    # The sprung CG moves by the payload's share of the sprung mass about it (the unsprung
    # masses sit on the centreline, so the sprung CG is cg_y m / m_s left of it).
    sprung_dx = (moment_x - added * _sprung_offset_x(p)) / sprung
    sprung_dy = (moment_y - added * p.cg_y * (p.mass / p.sprung_mass - 1.0)) / sprung
    return dataclasses.replace(
        p,
        mass=total,
        lf=p.lf - dx,
        lr=p.lr + dx,
        cg_y=p.cg_y + dy,
        cg_height=p.cg_height + dz,
        sprung_mass=sprung,
        sprung_cg_height=p.sprung_cg_height + sprung_dz,
        aero_x=p.aero_x - dx,
        aero_z=p.aero_z - dz,
        imu_x=p.imu_x - sprung_dx,
        imu_y=p.imu_y - sprung_dy,
        imu_z=p.imu_z - sprung_dz,
    )


def _sprung_offset_x(p: ModelParameters):
    """The sprung CG ahead of the whole-vehicle CG: the unsprung axles balance it."""
    unsprung_front, unsprung_rear = 2.0 * p.unsprung_front, 2.0 * p.unsprung_rear
    return (unsprung_rear * p.lr - unsprung_front * p.lf) / p.sprung_mass


def mass_properties(p: ModelParameters, payload) -> ca.SX:
    """:data:`MASS_PROPERTIES` of the loaded vehicle: ``[m', δx, y_c', h']``."""
    loaded = loaded_parameters(p, payload)
    return ca.vertcat(loaded.mass, p.lf - loaded.lf, loaded.cg_y, loaded.cg_height)


def payload_of(p: ModelParameters, properties) -> tuple:
    """The payload ``[mass, moment_x, moment_y, moment_z]`` whose :func:`mass_properties`
    are ``properties`` (``[m', δx, y_c', h']``): its inverse."""
    total, ahead, left, height = (properties[i] for i in range(4))
    return (total - p.mass, total * ahead, total * (left - p.cg_y), total * (height - p.cg_height))


def loaded_parameters_function(name: str = "loaded_parameters") -> ca.Function:
    """``name(p, payload[4]) -> p_loaded``: :func:`loaded_parameters` as a CasADi Function."""
    p_vector, p = ModelParameters.symbolic()
    payload = ca.SX.sym("payload", len(PAYLOAD_STATES))
    loaded = loaded_parameters(p, payload)
    values = ca.vertcat(*[getattr(loaded, key) for key in ModelParameters.names()])
    return ca.Function(name, [p_vector, payload], [values], ["p", "payload"], ["p_loaded"])
