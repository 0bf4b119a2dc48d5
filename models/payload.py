r"""A payload on the sprung body: combined mass, centre of mass and inertia.

A point mass :math:`m_p` at :math:`r_p` (ISO 8855 body axes from the vehicle file's
sprung CG) added to a rigid body of mass :math:`m`, centre :math:`c` and inertia
:math:`I` about :math:`c` (parallel-axis theorem):

.. math::
    m' = m + m_p, \quad c' = (m c + m_p r_p) / m', \quad
    I' = I + m\,\Pi(c - c') + m_p\,\Pi(r_p - c'), \quad
    \Pi(r) = (r^T r) E_3 - r r^T

The functions take numbers (numpy) or CasADi symbols, so the plant
(:mod:`wheelload.models.plant.dynamics`) and an online payload estimate share them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from wheelload.models.mass_properties import vehicle_mass_centre
from wheelload.models.vehicle.description import Vehicle

_SYMBOLIC = (ca.SX, ca.MX, ca.DM)


@dataclass(frozen=True, kw_only=True)
class Payload:
    """A point mass on the sprung body: kg; m from the file's sprung CG (x fwd, y left, z up)."""

    mass: float
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0

    def __post_init__(self) -> None:
        for key in ("mass", "x", "y", "z"):
            if not np.isfinite(getattr(self, key)):
                raise ValueError(f"payload '{key}' must be finite, got {getattr(self, key)}")
        if self.mass < 0.0:
            raise ValueError(f"payload 'mass' must be >= 0 kg, got {self.mass}")

    @property
    def position(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])

    @property
    def values(self) -> np.ndarray:
        """``[mass, x, y, z]``: the plant's payload inputs."""
        return np.array([self.mass, self.x, self.y, self.z])


@dataclass(frozen=True, kw_only=True)
class RigidBody:
    """Mass [kg], centre (3,) [m] and inertia (3, 3) about the centre [kg m^2]: numbers or
    CasADi expressions."""

    mass: Any
    centre: Any
    inertia: Any


def _symbolic(*values) -> bool:
    return any(isinstance(v, _SYMBOLIC) for v in values)


def _casadi(value):
    """``value`` as a CasADi column or matrix (numbers become a DM)."""
    return value if isinstance(value, _SYMBOLIC) else ca.DM(np.asarray(value, float))


def point_inertia(mass, offset):
    r"""Inertia of a point mass about a point ``offset`` from it: :math:`m\,\Pi(r)`."""
    if _symbolic(mass, offset):
        r = ca.vec(_casadi(offset))
        return mass * (ca.dot(r, r) * ca.DM.eye(3) - ca.mtimes(r, r.T))
    r = np.asarray(offset, float)
    return mass * (float(r @ r) * np.eye(3) - np.outer(r, r))


def with_point_mass(body: RigidBody, mass, position) -> RigidBody:
    """``body`` with a point mass ``mass`` at ``position`` (module docstring)."""
    total = body.mass + mass
    if _symbolic(body.mass, body.centre, body.inertia, mass, position):
        centre_b, position = ca.vec(_casadi(body.centre)), ca.vec(_casadi(position))
        inertia_b = _casadi(body.inertia)
    else:
        centre_b, position = np.asarray(body.centre, float), np.asarray(position, float)
        inertia_b = np.asarray(body.inertia, float)
    centre = (body.mass * centre_b + mass * position) / total
    inertia = (
        inertia_b
        + point_inertia(body.mass, centre_b - centre)
        + point_inertia(mass, position - centre)
    )
    return RigidBody(mass=total, centre=centre, inertia=inertia)


def with_payload(body: RigidBody, payload: Payload) -> RigidBody:
    """``body`` carrying ``payload`` (numbers)."""
    return with_point_mass(body, payload.mass, payload.position)


def inertia_about(body: RigidBody, point):
    r"""Inertia of ``body`` about ``point``: :math:`I + m\,\Pi(c - p)`."""
    if _symbolic(body.mass, body.centre, body.inertia, point):
        offset = ca.vec(_casadi(body.centre)) - ca.vec(_casadi(point))
        return _casadi(body.inertia) + point_inertia(body.mass, offset)
    return body.inertia + point_inertia(body.mass, np.asarray(body.centre) - np.asarray(point))


def sprung_body(vehicle: Vehicle) -> RigidBody:
    """The vehicle file's sprung body: its mass at the origin, principal inertia."""
    return RigidBody(
        mass=vehicle.mass.sprung, centre=np.zeros(3), inertia=np.diag(vehicle.mass.inertia)
    )


def loaded_mass_properties(vehicle: Vehicle, payload: Payload) -> np.ndarray:
    r"""``[mass, cg_x, cg_y, cg_height]`` of the whole vehicle carrying ``payload``.

    cg_x, cg_y from the file's whole-vehicle CG
    (:func:`~wheelload.models.mass_properties.vehicle_mass_centre`), cg_height above
    ground, in the file's reference state (travel zero).
    """
    centre = vehicle_mass_centre(vehicle)
    reference = np.array([centre.offset_x, 0.0, centre.height - vehicle.geometry.cg_height])
    whole = RigidBody(mass=vehicle.mass.total, centre=reference, inertia=np.zeros((3, 3)))
    loaded = with_payload(whole, payload)
    return np.array(
        [
            loaded.mass,
            loaded.centre[0] - centre.offset_x,
            loaded.centre[1],
            loaded.centre[2] + vehicle.geometry.cg_height,
        ]
    )
