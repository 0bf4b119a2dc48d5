"""The moving-horizon estimator behind the ``Estimator`` interface (estimators.protocol).

:class:`~wheelload.estimators.mhe.estimator.MovingHorizonEstimator` needs the nominal
sample interval to set up its window (cost scale, steady-state arrival);
this adapter fixes it at construction so that ``initial_state()`` takes no
argument. ``run`` uses the log's median interval, so ``run`` and repeated
``step`` agree when ``interval`` is that median (e.g. 0.01 s at 100 Hz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from wheelload.estimators.mhe.settings import MheSettings
from wheelload.estimators.mhe.state import MheEstimate, MheState
from wheelload.estimators.protocol import MethodInfo
from wheelload.estimators.types import Sample, Signals
from wheelload.models import Vehicle

NOMINAL_INTERVAL = 0.01  # s, 100 Hz


@dataclass(frozen=True, kw_only=True)
class MheOptions:
    """Options of the MHE (``build("mhe", vehicle, **options)``)."""

    settings: MheSettings | None = None  # window, constraint, losses; None: MheSettings()
    interval: float = NOMINAL_INTERVAL  # nominal sample interval [s] of initial_state()


class MheMethod:
    """The MHE with ``initial_state()`` at a fixed nominal interval (module docstring)."""

    def __init__(
        self,
        vehicle: Vehicle,
        settings: MheSettings | None = None,
        *,
        interval: float = NOMINAL_INTERVAL,
    ) -> None:
        if not (math.isfinite(interval) and interval > 0):
            raise ValueError(f"the nominal sample interval must be > 0, got {interval}")
        # OSQP and scipy.sparse load here, not when the registry lists the methods.
        from wheelload.estimators.mhe.estimator import MovingHorizonEstimator

        self.vehicle = vehicle
        self.mhe = MovingHorizonEstimator(vehicle, settings)
        self.interval = interval
        self.name = self.mhe.name

    def initial_state(self) -> MheState:
        return self.mhe.initial_state(self.interval)

    def step(self, state: MheState, sample: Sample, dt: float) -> tuple[MheState, MheEstimate]:
        return self.mhe.step(state, sample, dt)

    def run(self, signals: Signals) -> MheEstimate:
        return self.mhe.run(signals)


INFO = MethodInfo(
    name="mhe",
    description="moving-horizon estimator N=10, soft equilibrium, OSQP",
    reference="Rao, Rawlings & Lee 2001; Siegloff & Choi eq. 12-17",
    build=MheMethod,
    options=MheOptions,
)
