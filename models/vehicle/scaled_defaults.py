r"""Defaults of the vehicle file that scale with the car, derived from the file's own mass.

The filter's defaults that carry a force, a mass or their squares (the reported-sigma
model's coefficients, the payload filter's priors and densities) were fitted on the two
bundled vehicles, of :data:`CALIBRATED_MASSES` (the sports car and the SUV; ``wheelload
study sigma`` fits one set for both). A file that does not set one gets

.. math:: v = v_{fit}\,(m / \bar m)^k, \qquad \bar m = \min(\max(m, m_{lo}), m_{hi})

with :math:`m` its ``mass.total`` and :math:`k` the key's power in :data:`MASS_POWERS`
(1 for N, N per m/s^2, kg; 2 for N^2 s and kg^2/s): the fitted value within the fitted
range of masses, scaled from its nearer end outside it. So a 284 kg Formula Student car
runs from a file that states only its own values (no default exceeds what its ranges in
``models/vehicle/plausibility.py`` allow for that car), and the bundled cars keep the
values fitted on them. A key the file sets is kept as it is.

Example
-------
>>> with_scaled_defaults({"mass": {"total": 284.0}, "filter": {}}, defaults)["filter"]
{'sigma_floor': 2.89..., ...}
"""

from __future__ import annotations

import copy
import math

#: kg, the masses of the vehicles the defaults were fitted on (models/vehicles/sports_car.toml,
#: suv.toml)
CALIBRATED_MASSES = (1613.2, 2275.0)
_SIGMA_KEYS = ("sigma_floor", "sigma_ax", "sigma_ay", "sigma_travel_rate", "sigma_travel",
               "sigma_no_travel", "sigma_no_travel_ax", "sigma_no_travel_ay",
               "sigma_no_travel_az", "sigma_no_travel_lateral")  # fmt: skip
#: file key (its table's parts, then the key) -> power of the mass ratio
MASS_POWERS: dict[tuple[str, ...], int] = {
    # the reported sigma (estimators/kf/reported_std.py): N, N per m/s^2, N per m/s, N per m
    **{("filter", key): 1 for key in _SIGMA_KEYS},
    # the payload filter (estimators/kf/payload.py): kg, kg m; N^2 s and kg^2/s
    ("filter", "payload", "mass_std"): 1,
    ("filter", "payload", "apparent_mass"): 1,
    ("filter", "payload", "apparent_moment"): 1,
    ("filter", "payload", "residual_density"): 2,
    ("filter", "payload", "drift_density"): 2,
    ("filter", "payload", "standstill_density"): 2,
}


def mass_ratio(mass: float) -> float:
    """:math:`m / \\bar m`: 1 within :data:`CALIBRATED_MASSES`, else the ratio to the nearer end."""
    low, high = CALIBRATED_MASSES
    return mass / min(max(mass, low), high)


def scaled(value: float | tuple[float, ...], ratio: float, power: int) -> float | list[float]:
    """``value`` times ``ratio ** power`` (each entry of a vector)."""
    if isinstance(value, tuple):
        return [v * ratio**power for v in value]
    return value * ratio**power


def with_scaled_defaults(table: dict, defaults: dict[tuple[str, ...], object]) -> dict:
    """A copy of the parsed file ``table`` with each :data:`MASS_POWERS` key it does not set
    filled in from ``defaults`` (the reference car's values) scaled to its ``mass.total``;
    ``table`` itself unchanged. A file without a usable mass is returned as it is (its
    error is the reader's)."""
    mass = table.get("mass", {}).get("total") if isinstance(table.get("mass"), dict) else None
    if isinstance(mass, bool) or not isinstance(mass, int | float) or not math.isfinite(mass):
        return table
    if not mass > 0 or not isinstance(table.get("filter"), dict):
        return table
    ratio = mass_ratio(float(mass))
    result = dict(table, filter=copy.deepcopy(table["filter"]))
    for key, power in MASS_POWERS.items():
        *parents, name = key
        node = result
        for part in parents:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                break  # not a table: the reader names the key
        else:
            if name not in node:
                node[name] = scaled(defaults[key], ratio, power)
    return result
