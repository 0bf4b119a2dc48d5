r"""Where the wheels are and how far their centres stand off the road, from the description.

Shared by the estimators that need wheel positions (the body-attitude terms, the tyre-force
methods) and by the plant, so each is written once:

- wheel centres in the body's ground plane from the sprung CG, FL, FR, RL, RR:
  :math:`(l_f, \pm t_f/2)`, :math:`(-l_r, \pm t_r/2)` (ISO 8855, y to the left);
- static loaded radius: :math:`R_i - F_{z,i} / k_{t,i}`, the tyre's free radius less its
  deflection under the static load ``loads`` (N, FL..RR);
- effective rolling radius (:func:`rolling_radius`): the free radius less a third of the
  deflection.
"""

from __future__ import annotations

from wheelload.models.vehicle.description import Geometry, Tyres


def wheel_centres(geometry: Geometry) -> tuple[tuple[float, float], ...]:
    """Wheel centres ``(x, y)`` [m] from the sprung CG, rows FL, FR, RL, RR."""
    g = geometry
    return (
        (g.lf, 0.5 * g.track_front),
        (g.lf, -0.5 * g.track_front),
        (-g.lr, 0.5 * g.track_rear),
        (-g.lr, -0.5 * g.track_rear),
    )


def loaded_radii(tyres: Tyres, loads) -> tuple[float, ...]:
    """Static loaded radius [m] of each wheel FL..RR under the static ``loads`` [N]."""
    radii = (tyres.radius_front,) * 2 + (tyres.radius_rear,) * 2
    rates = (tyres.vertical_stiffness_front,) * 2 + (tyres.vertical_stiffness_rear,) * 2
    return tuple(r - f / k for r, f, k in zip(radii, loads, rates))


def rolling_radius(free_radius, deflection):
    r"""Effective rolling radius [m]: :math:`R_e = R_0 - \rho / 3`, the free radius less a
    third of the deflection :math:`\rho` (a radial tyre's belt barely stretches, so it rolls
    on a radius between the free and the loaded one; Pacejka, Tire and Vehicle Dynamics,
    ch. 7). The speed of the wheel centre over the road at zero slip is :math:`R_e \omega`."""
    return free_radius - deflection / 3.0
