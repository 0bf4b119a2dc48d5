r"""Optional wheel and tyre sections of a vehicle file, read by the tyre-force estimators.

- ``[wheels]``: what eq. 1 of the corner-based paper needs of each wheel,
  :math:`F_x = (T - J \dot\omega)/R - f_r F_z`: the spin inertia :math:`J` per axle and
  the rolling-resistance coefficient :math:`f_r` (the loaded radius :math:`R` follows
  from ``[tyres]`` and the static loads). Required by ``tyre-pid``, ``tyre-lateral``
  and ``tyre-forces``.
- ``[cornering]``: beyond the paper, which assumes no tyre model: the tyres' lateral load
  sensitivity (magic-formula :math:`F_{z0}`, :math:`\mu_{y0}`, :math:`p_{D2}`,
  :math:`p_{Ky2}`), with which the lateral filter splits an axle's force left/right
  (:func:`~wheelload.models.family.tyre_forces.tyre_split`). Without it the split is
  the normal-load share the paper names (§III-B).

These describe the estimator's car, as the rest of the file does; the ``[plant]``
section describes the simulated one, which may differ.
"""

from __future__ import annotations

from dataclasses import dataclass

from wheelload.models.vehicle.section_checks import require_non_negative, require_positive


@dataclass(frozen=True, kw_only=True)
class Wheels:
    """``[wheels]``: spin inertia per axle and the rolling-resistance coefficient."""

    spin_inertia_front: float  # kg m^2, wheel + tyre + disc + hub about the spin axis
    spin_inertia_rear: float  # kg m^2
    rolling_resistance: float  # -, f_r

    def _check(self) -> None:
        require_positive(self, "spin_inertia_front")
        require_positive(self, "spin_inertia_rear")
        require_non_negative(self, "rolling_resistance")


@dataclass(frozen=True, kw_only=True)
class Cornering:
    """``[cornering]``: the tyres' lateral load sensitivity (magic formula, Pacejka 2012)."""

    nominal_load_front: float  # N, F_z0
    nominal_load_rear: float  # N
    friction: float  # -, mu_y0 (p_Dy1)
    friction_load_sensitivity: float  # -, p_Dy2
    cornering_load: float  # -, p_Ky2: load of the cornering stiffness's peak over F_z0

    def _check(self) -> None:
        for key in ("nominal_load_front", "nominal_load_rear", "friction", "cornering_load"):
            require_positive(self, key)
