"""A log as the per-sample stream of the ``Estimator`` protocol (``wheelload.estimators.protocol``).

:func:`samples` turns :class:`~wheelload.estimators.types.Signals` into
:class:`~wheelload.estimators.types.Sample` s (the body-rate derivative
filtered as in the KF's ``run``); :func:`step_through` calls an estimator's
``step`` on each of them, the reference every ``run`` must reproduce.

Example
-------
>>> estimate = step_through(build("C", vehicle), signals)
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from wheelload.estimators.logs.signals import (
    DEFAULT_RATE_FILTER,
    RateDerivativeFilter,
    rate_derivatives,
)
from wheelload.estimators.protocol import Estimator, sample_intervals
from wheelload.estimators.result import Estimate
from wheelload.estimators.types import Sample, Signals


def samples(
    signals: Signals, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
) -> Iterator[Sample]:
    """The log's samples in order, with the body rates, their (causal, filtered by
    ``rate_filter``) derivative and the hub accelerometers where the log has them."""
    rate_dots = (
        rate_derivatives(signals, rate_filter) if signals.rates is not None else signals.rate_dots
    )
    for k in range(len(signals)):
        yield Sample(
            d=signals.d[k],
            v=signals.v[k],
            acc=signals.acc[k],
            vx=float(signals.vx[k]),
            rates=None if signals.rates is None else signals.rates[k],
            rate_dots=None if rate_dots is None else rate_dots[k],
            hub=None if signals.hub is None else signals.hub[k],
            spin=None if signals.spin is None else signals.spin[k],
            torque=None if signals.torque is None else signals.torque[k],
            steer=None if signals.steer is None else float(signals.steer[k]),
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
        fx=_joined([e.fx for e in estimates]),
        fy=_joined([e.fy for e in estimates]),
        fx_std=_joined([e.fx_std for e in estimates]),
        fy_std=_joined([e.fy_std for e in estimates]),
    )


def _joined(parts: list[np.ndarray | None]) -> np.ndarray | None:
    """The rows of ``parts`` stacked, or None when any is None (a method without them)."""
    return None if any(p is None for p in parts) else np.concatenate(parts)


def step_through(estimator: Estimator, signals: Signals, state: Any = None) -> Estimate:
    """``estimator.step`` over every sample from ``state`` (default: a fresh initial state).

    The reference that ``run`` must reproduce; intervals as in the KF's ``run``
    (the first sample reuses the first interval), the body-rate derivatives filtered as
    the estimator's vehicle file says.
    """
    state = estimator.initial_state() if state is None else state
    estimates = []
    rate_filter = RateDerivativeFilter.of(estimator.vehicle)
    for sample, dt in zip(samples(signals, rate_filter), sample_intervals(signals.t)):
        state, estimate = estimator.step(state, sample, float(dt))
        estimates.append(estimate)
    return concatenate(estimates, signals.t)
