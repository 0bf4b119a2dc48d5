"""Aerodynamic forces of the body (Siegloff & Choi eq. 18).

``p`` is a :class:`~wheelload.models.parameters.ModelParameters` (numbers or symbols).
"""

from __future__ import annotations


def aero_forces(vx, p):
    r"""Aerodynamic lift and drag magnitudes (eq. 18): :math:`\tfrac12 \rho V_x^2 A c`."""
    pressure = 0.5 * p.air_density * vx**2 * p.reference_area
    return pressure * p.lift_coefficient, pressure * p.drag_coefficient
