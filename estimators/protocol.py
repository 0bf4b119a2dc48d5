"""The one interface every wheel-load estimator of the family meets.

An estimator is built from a :class:`~wheelload.models.Vehicle` (through the
registry, :mod:`wheelload.estimators.registry`) and offers

- ``name``: a label for tables and figures;
- ``initial_state()``: an explicit, immutable state object (a frozen
  dataclass or a tuple of arrays the estimator never mutates);
- ``step(state, sample, dt) -> (state, estimate)``: one sample; the estimate
  has one row and ``t = [nan]`` (a :class:`Sample` carries no time stamp);
- ``run(signals) -> Estimate``: a whole log from a fresh ``initial_state()``,
  the same numbers as repeated ``step``
  (:func:`~wheelload.estimators.samples.step_through`).

Beside the protocol: the :class:`Sample` a ``step`` takes and the intervals
between samples (:func:`sample_intervals`), the :class:`MethodInfo` each
registered method exports as ``INFO`` (with the frozen dataclass of its
options, :class:`NoOptions` for none), and the :class:`SuspensionModel` a
family method is built on.

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
>>> state, one = estimator.step(estimator.initial_state(), sample, 0.01)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from wheelload.estimators.result import Estimate
from wheelload.estimators.suspension_choice import DEFAULT_MODEL as DEFAULT_MODEL
from wheelload.estimators.suspension_choice import SuspensionModel as SuspensionModel
from wheelload.estimators.types import Sample, Signals


def sample_intervals(t: np.ndarray) -> np.ndarray:
    """Interval before each sample; the first sample reuses the first interval."""
    dt = np.diff(t)
    return np.concatenate([dt[:1], dt])


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


@dataclass(frozen=True, kw_only=True)
class NoOptions:
    """The options of a method that takes none beside the vehicle (and its model)."""


@dataclass(frozen=True, kw_only=True)
class MethodInfo:
    """One registered method: its name, a one-line description, its source and its builder.

    ``build(vehicle, **options)``, the keyword options those of ``options`` (a frozen
    dataclass, one field a keyword, with its default and a one-line comment; the registry
    checks names and types against it); a method with ``model_choice`` also takes
    ``build(vehicle, suspension=SuspensionModel...)``. ``compiled_batch``: the method
    offers the compiled whole-log paths of ``wheelload estimate`` (static loads measured
    from the log, the chunked lean path, ``smooth``). Each method's module exports its
    ``INFO`` (:mod:`wheelload.estimators.registry` collects them).
    """

    name: str
    description: str
    reference: str
    build: Callable[..., Estimator]
    model_choice: bool = False
    options: type = NoOptions
    compiled_batch: bool = False

    def __post_init__(self) -> None:
        if not self.name or any(c.isspace() or c == "," for c in self.name):
            raise ValueError(
                f"method name must be non-empty without spaces or commas: {self.name!r}"
            )
        if not callable(self.build):
            raise TypeError(f"method {self.name}: build must be callable")
        frozen = dataclasses.is_dataclass(self.options) and self.options.__dataclass_params__.frozen
        if not (isinstance(self.options, type) and frozen):
            raise TypeError(f"method {self.name}: options must be a frozen dataclass")
