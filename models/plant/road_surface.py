"""The road under the plant: centre-line tables sampled by arc length.

A road is a planar centre line of curvature :math:`\\kappa(s)` (> 0 turns
left) carrying an elevation :math:`z_c(s)`, a grade :math:`dz_c/ds`, a bank
slope :math:`\\beta(s) = \\partial z / \\partial n` (n to the left; > 0 when
the left edge is higher) and two roughness profiles, one per wheel track:

.. math:: z(s, n) = z_c(s) + n \\beta(s) + r_{L/R}(s)

The plant looks the columns up with one linear CasADi interpolant, so every
contact point gets its own elevation.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

COLUMNS = ("elevation", "grade", "bank", "curvature", "roughness_left", "roughness_right")


@dataclass(frozen=True, kw_only=True)
class RoadSurface:
    """Road columns on an increasing arc-length grid ``s`` [m]; all arrays of one length."""

    s: np.ndarray
    elevation: np.ndarray  # m
    grade: np.ndarray  # -, dz/ds
    bank: np.ndarray  # -, dz/dn
    curvature: np.ndarray  # 1/m
    roughness_left: np.ndarray  # m
    roughness_right: np.ndarray  # m

    def __post_init__(self) -> None:
        s = np.asarray(self.s, float)
        if s.ndim != 1 or s.size < 2 or not np.all(np.diff(s) > 0):
            raise ValueError("road grid 's' must be a strictly increasing 1-D array")
        for key in COLUMNS:
            column = np.asarray(getattr(self, key), float)
            if column.shape != s.shape:
                raise ValueError(f"road column '{key}' has shape {column.shape}, 's' {s.shape}")
            if not np.all(np.isfinite(column)):
                raise ValueError(f"road column '{key}' has non-finite values")

    def table(self) -> np.ndarray:
        """Columns stacked as a (6, N) array in :data:`COLUMNS` order."""
        return np.vstack([np.asarray(getattr(self, key), float) for key in COLUMNS])

    def height(self, s, n, left: bool = True) -> np.ndarray:
        """Road height [m] at arc length ``s`` and lateral offset ``n`` (numpy)."""
        rough = self.roughness_left if left else self.roughness_right
        return (
            np.interp(s, self.s, self.elevation)
            + np.asarray(n) * np.interp(s, self.s, self.bank)
            + np.interp(s, self.s, rough)
        )


def road_lookup(road: RoadSurface, name: str = "road") -> ca.Function:
    """``name(s) -> [elevation, grade, bank, curvature, roughness_left, roughness_right]``."""
    data = road.table()
    return ca.interpolant(name, "linear", [np.asarray(road.s, float)], data.ravel(order="F"))
