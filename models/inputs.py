"""The per-sample input vector ``u`` every model Function and estimator step takes.

One ordered layout, so that a new model term extends :data:`INPUTS` here and
every estimator, the generated C's input struct and its example program
follow with no other edit. Channels after ``vx`` are optional: a log without
them leaves them non-finite and the terms that need them are dropped for that
sample (``wheelload.models.terms``).

Example
-------
>>> INPUTS.index("ax")
8
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from wheelload.models.conventions import WHEELS

TRAVEL = tuple(f"d_{w}" for w in WHEELS)  # m, compression
TRAVEL_RATE = tuple(f"v_{w}" for w in WHEELS)  # m/s
SPECIFIC_FORCE = ("ax", "ay", "az")  # m/s^2, IMU sensor axes, gravity included
SPEED = ("vx",)  # m/s
BODY_RATES = ("wx", "wy", "wz")  # rad/s, IMU sensor axes
BODY_RATE_DERIVATIVES = ("wx_dot", "wy_dot", "wz_dot")  # rad/s^2, filtered derivative
HUB_ACCELERATION = tuple(f"az_{w}" for w in WHEELS)  # m/s^2, hub specific force, body z

#: Order of the per-sample input vector ``u``.
INPUTS = (
    TRAVEL
    + TRAVEL_RATE
    + SPECIFIC_FORCE
    + SPEED
    + BODY_RATES
    + BODY_RATE_DERIVATIVES
    + HUB_ACCELERATION
)
#: Inputs a log may lack (their terms are then dropped, not the updates).
OPTIONAL_INPUTS = BODY_RATES + BODY_RATE_DERIVATIVES + HUB_ACCELERATION


def input_index(names: tuple[str, ...]) -> list[int]:
    """Positions of ``names`` in :data:`INPUTS`."""
    return [INPUTS.index(name) for name in names]


@dataclass(frozen=True, kw_only=True)
class ModelInputs:
    """The input vector split into its channels (CasADi expressions or numbers)."""

    d: Any  # (4,)
    v: Any  # (4,)
    acc: Any  # (3,) sensor axes
    vx: Any
    rates: Any  # (3,) sensor axes
    rate_dots: Any  # (3,) sensor axes
    hub: Any  # (4,)

    @classmethod
    def unpack(cls, u) -> ModelInputs:
        def part(names):
            first = INPUTS.index(names[0])
            return u[first : first + len(names)]

        return cls(
            d=part(TRAVEL),
            v=part(TRAVEL_RATE),
            acc=part(SPECIFIC_FORCE),
            vx=u[INPUTS.index("vx")],
            rates=part(BODY_RATES),
            rate_dots=part(BODY_RATE_DERIVATIVES),
            hub=part(HUB_ACCELERATION),
        )


def input_description(name: str) -> str:
    """One-line meaning and unit of input ``name`` (for generated headers)."""
    groups = (
        (TRAVEL, "suspension travel [m], compression > 0"),
        (TRAVEL_RATE, "travel rate [m/s]"),
        (SPECIFIC_FORCE, "IMU specific force, sensor axes [m/s^2]"),
        (SPEED, "forward speed [m/s]"),
        (BODY_RATES, "IMU angular rate, sensor axes [rad/s] (optional)"),
        (BODY_RATE_DERIVATIVES, "filtered derivative of the rate [rad/s^2] (optional)"),
        (HUB_ACCELERATION, "hub specific force along body z [m/s^2] (optional)"),
    )
    for names, text in groups:
        if name in names:
            return text
    raise KeyError(name)


def input_vector(
    *,
    d,
    acc,
    vx,
    v=None,
    rates=None,
    rate_dots=None,
    hub=None,
):
    """Numeric inputs in :data:`INPUTS` order, shape (len(INPUTS), n) (or (len(INPUTS),)).

    Each channel group is an array of shape (n, k) or (k,); ``v`` defaults to
    zero, the optional groups to NaN (not logged).
    """
    import numpy as np

    d = np.asarray(d, dtype=float)
    single = d.ndim == 1
    n = 1 if single else d.shape[0]

    def rows(values, width, fill):
        if values is None:
            return np.full((width, n), fill)
        return np.asarray(values, dtype=float).reshape(n, width).T

    u = np.vstack(
        [
            rows(d, 4, 0.0),
            rows(v, 4, 0.0),
            rows(acc, 3, 0.0),
            rows(vx, 1, 0.0),
            rows(rates, 3, np.nan),
            rows(rate_dots, 3, np.nan),
            rows(hub, 4, np.nan),
        ]
    )
    return u[:, 0] if single else u
