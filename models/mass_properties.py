"""Whole-vehicle mass centre and static wheel loads.

The vehicle file gives the sprung-mass CG (Table I); the equilibrium relations
(paper eq. 14-16) act on the whole vehicle, so the unsprung masses are added
at their axles, at wheel-centre height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.vehicle.description import Vehicle


@dataclass(frozen=True, kw_only=True)
class MassCentre:
    """Whole-vehicle CG: distances to the axles and height above ground [m]."""

    lf: float
    lr: float
    height: float
    offset_x: float  # forward offset from the sprung CG


def vehicle_mass_centre(vehicle: Vehicle) -> MassCentre:
    r"""Mass-weighted CG of sprung body and unsprung axles.

    .. math:: x_c = (m_{uf} l_f - m_{ur} l_r) / m, \quad
              h = (m_s h_s + m_{uf} r_f + m_{ur} r_r) / m
    """
    m, g, t = vehicle.mass, vehicle.geometry, vehicle.tyres
    parts = m.sprung + m.unsprung_front + m.unsprung_rear
    offset_x = (m.unsprung_front * g.lf - m.unsprung_rear * g.lr) / parts
    height = (
        m.sprung * g.cg_height + m.unsprung_front * t.radius_front + m.unsprung_rear * t.radius_rear
    ) / parts
    return MassCentre(lf=g.lf - offset_x, lr=g.lr + offset_x, height=height, offset_x=offset_x)


def static_loads(vehicle: Vehicle) -> np.ndarray:
    r"""Static wheel loads on level ground, order FL, FR, RL, RR [N].

    .. math:: F_{z,f} = \tfrac12 m g \, l_r / (l_f + l_r), \quad
              F_{z,r} = \tfrac12 m g \, l_f / (l_f + l_r)
    """
    centre = vehicle_mass_centre(vehicle)
    weight = vehicle.mass.total * GRAVITY
    front = 0.5 * weight * centre.lr / (centre.lf + centre.lr)
    rear = 0.5 * weight * centre.lf / (centre.lf + centre.lr)
    return np.array([front, front, rear, rear])
