"""The one interface every wheel-load estimator of the family meets.

An estimator is built from a :class:`~wheelload.models.Vehicle` (through the
registry, :mod:`wheelload.estimators.registry`) and offers

- ``name``: a label for tables and figures;
- ``initial_state()``: an explicit, immutable state object (a frozen
  dataclass or a tuple of arrays the estimator never mutates);
- ``step(state, sample, dt) -> (state, estimate)``: one sample; the estimate
  has one row and ``t = [nan]`` (a :class:`Sample` carries no time stamp);
- ``run(signals) -> Estimate``: a whole log from a fresh ``initial_state()``,
  the same numbers as :func:`step_through` (repeated ``step``).

Conventions shared by every member:

- wheel order FL, FR, RL, RR, SI units; ``Estimate.loads`` and ``std`` (n, 4),
  ``residual`` (n, 3) is :math:`b - A x` of the method's own loads with the
  equilibrium of ``wheelload.models.equilibrium_function``;
- a method without a standard deviation returns ``std`` zeros and
  ``has_std=False``;
- never NaN or Inf: a missing input skips the update that needs it and sets
  the matching :class:`~wheelload.estimators.result.StepFlag` bit; an interval
  ``dt`` that is not in (0, MAX_INTERVAL) holds the state and sets
  ``STEP_REJECTED``.

Example
-------
>>> estimator = build("C", vehicle)
>>> estimate = estimator.run(signals)
>>> state, one = estimator.step(estimator.initial_state(), next(samples(signals)), 0.01)
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np

from wheelload.estimators.kf.two_stage import Sample, sample_intervals
from wheelload.estimators.logs.signals import Signals, rate_derivatives
from wheelload.estimators.result import Estimate


@runtime_checkable
class Estimator(Protocol):
    """A wheel-load estimator: explicit state, per-sample ``step`` and whole-log ``run``."""

    name: str

    def initial_state(self) -> Any:
        """The state before the first sample (immutable)."""
        ...

    def step(self, state: Any, sample: Sample, dt: float) -> tuple[Any, Estimate]:
        """One sample ``dt`` [s] after the previous: the new state and a 1-row estimate."""
        ...

    def run(self, signals: Signals) -> Estimate:
        """A whole log from a fresh initial state; same numbers as repeated :meth:`step`."""
        ...


def samples(signals: Signals) -> Iterator[Sample]:
    """The log's samples in order, with the body rates, their (causal, filtered)
    derivative and the hub accelerometers where the log has them."""
    rate_dots = rate_derivatives(signals) if signals.rates is not None else signals.rate_dots
    for k in range(len(signals)):
        yield Sample(
            d=signals.d[k],
            v=signals.v[k],
            acc=signals.acc[k],
            vx=float(signals.vx[k]),
            rates=None if signals.rates is None else signals.rates[k],
            rate_dots=None if rate_dots is None else rate_dots[k],
            hub=None if signals.hub is None else signals.hub[k],
        )


def concatenate(estimates: Sequence[Estimate], t: np.ndarray) -> Estimate:
    """One :class:`Estimate` of the 1-row estimates of consecutive steps, time stamps ``t``."""
    return Estimate(
        t=np.asarray(t, float).copy(),
        loads=np.concatenate([e.loads for e in estimates]),
        std=np.concatenate([e.std for e in estimates]),
        residual=np.concatenate([e.residual for e in estimates]),
        flags=np.concatenate([np.atleast_1d(e.flags) for e in estimates]).astype(np.int64),
        has_std=all(e.has_std for e in estimates),
    )


def step_through(estimator: Estimator, signals: Signals, state: Any = None) -> Estimate:
    """``estimator.step`` over every sample from ``state`` (default: a fresh initial state).

    The reference that ``run`` must reproduce; intervals as in the KF's ``run``
    (the first sample reuses the first interval).
    """
    state = estimator.initial_state() if state is None else state
    estimates = []
    for sample, dt in zip(samples(signals), sample_intervals(signals.t)):
        state, estimate = estimator.step(state, sample, float(dt))
        estimates.append(estimate)
    return concatenate(estimates, signals.t)
