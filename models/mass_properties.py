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


def level_static_loads(mass, lf, lr) -> tuple:
    r"""Static wheel loads on level ground FL, FR, RL, RR [N] of whole-vehicle mass and CG.

    .. math:: F_{z,f} = \tfrac12 m g \, l_r / (l_f + l_r), \quad
              F_{z,r} = \tfrac12 m g \, l_f / (l_f + l_r)

    Numbers or CasADi symbols (the model parameters derive their static loads from it:
    :func:`wheelload.models.parameters.derived_values`).
    """
    weight = mass * GRAVITY
    front = 0.5 * weight * lr / (lf + lr)
    rear = 0.5 * weight * lf / (lf + lr)
    return (front, front, rear, rear)


def static_loads(vehicle: Vehicle) -> np.ndarray:
    """Static wheel loads on level ground, order FL, FR, RL, RR [N] (:func:`level_static_loads`)."""
    centre = vehicle_mass_centre(vehicle)
    return np.array(level_static_loads(vehicle.mass.total, centre.lf, centre.lr))
