r"""The payload a simulated car carries over time: constant, or changed at a stop.

A change at time :math:`T` (a passenger gets in) blends the payload's mass and first
moment from the old to the new one with a cosine ramp :math:`w(t)` over :data:`RAMP`:

.. math:: m(t) = (1 - w) m_0 + w m_1, \quad
          m(t) r(t) = (1 - w) m_0 r_0 + w m_1 r_1

so the combined centre of mass moves smoothly and ends at the new payload's. The
plant takes ``[m, r]`` as inputs, held over each output sample
(:func:`~wheelload.studies.drive.simulation.simulate`). The mass is taken on at the
body's velocity: meant for a car standing still (the simulation checks that the
scenario stands then).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from wheelload.models.payload import Payload
from wheelload.studies.drive.roads import smooth_step

RAMP = 1.5  # s, a passenger getting in


@dataclass(frozen=True, kw_only=True)
class PayloadChange:
    """The payload becomes ``payload`` from ``time`` [s] on (over :data:`RAMP`)."""

    time: float
    payload: Payload

    def __post_init__(self) -> None:
        if not (np.isfinite(self.time) and self.time >= 0.0):
            raise ValueError(f"payload change time must be >= 0 s, got {self.time}")


@dataclass(frozen=True, kw_only=True)
class PayloadSchedule:
    """The payload at the start, and an optional change."""

    initial: Payload = Payload(mass=0.0)
    change: PayloadChange | None = None

    def at(self, t: float) -> np.ndarray:
        """``[mass, x, y, z]`` at time ``t`` (the plant's payload inputs)."""
        if self.change is None:
            return self.initial.values
        w = float(smooth_step(t, self.change.time, RAMP))
        old, new = self.initial, self.change.payload
        mass = (1.0 - w) * old.mass + w * new.mass
        if mass <= 0.0:
            return np.array([0.0, *(new.position if w > 0.5 else old.position)])
        moment = (1.0 - w) * old.mass * old.position + w * new.mass * new.position
        return np.array([mass, *(moment / mass)])

    def moving(self) -> tuple[float, float] | None:
        """The time span [s] in which the payload changes, or None."""
        if self.change is None:
            return None
        return (self.change.time, self.change.time + RAMP)

    def describe(self) -> dict:
        """The schedule for the log metadata."""
        return {
            "initial": dataclasses.asdict(self.initial),
            "change": None if self.change is None else dataclasses.asdict(self.change),
            "ramp_s": RAMP,
            "frame": "point mass on the sprung body; kg, m from the vehicle file's sprung CG, "
            "ISO 8855 body axes (x forward, y left, z up)",
        }
