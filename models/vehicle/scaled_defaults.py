r"""Defaults of the vehicle file that scale with the car, derived from the file's own mass.

The filter's defaults that carry a force, a mass or their squares (the reported-sigma
model's coefficients, the payload filter's priors and densities) were calibrated on the
bundled sports car, :data:`REFERENCE_MASS`. A file that does not set one gets

.. math:: v = v_{ref}\,(m / m_{ref})^k

with :math:`m` its ``mass.total`` and :math:`k` the key's power in :data:`MASS_POWERS`
(1 for N, N per m/s^2, kg; 2 for N^2 s and kg^2/s), so that a 284 kg Formula Student car
or a 2.3 t SUV runs from a file that states only its own values: no default exceeds
what its ranges (``models/vehicle/plausibility.py``) allow for that car. A key the file
sets is kept as it is.

Example
-------
>>> with_scaled_defaults({"mass": {"total": 284.0}, "filter": {}}, defaults)["filter"]
{'sigma_no_travel_az': 50.77..., ...}
"""

from __future__ import annotations

import copy
import math

#: kg, the mass of the vehicle the defaults were calibrated on (models/vehicles/sports_car.toml)
REFERENCE_MASS = 1613.2
_SIGMA_KEYS = ("sigma_floor", "sigma_ax", "sigma_ay", "sigma_travel_rate", "sigma_travel",
               "sigma_no_travel", "sigma_no_travel_ax", "sigma_no_travel_ay",
               "sigma_no_travel_az")  # fmt: skip
#: file key (its table's parts, then the key) -> power of m / REFERENCE_MASS
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
    ratio = float(mass) / REFERENCE_MASS
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
