"""Runner of the family methods: one masked CasADi step Function, looped in compiled C.

Every method of this package is one CasADi Function whose inputs are, in order,

- the carried state (one or more arrays; the first ``len(initial)`` inputs,
  returned as the first outputs),
- the per-sample inputs ``u`` in the models' :data:`~wheelload.models.INPUTS`
  order (the two-stage KF's), ``u_valid`` (1 where the input is finite) and
  the interval ``dt``,
- any further per-sample inputs that depend on the interval alone (e.g. a
  transition matrix, :meth:`StepMethod.interval_inputs`, named in
  :attr:`StepMethod.interval_names`),
- fixed vectors (model parameters, the method's constants),

and whose outputs after the carried state are ``loads`` (4), ``std`` (4),
``residual`` (3) and ``flags`` (1, a sum of
:class:`~wheelload.estimators.result.StepFlag` values).
:meth:`StepMethod.step` calls the Function once; :meth:`StepMethod.run` loops
it in generated C (:class:`~wheelload.estimators.loops.compiled.CompiledLoop`, as
the KF), in chunks of :data:`CHUNK` samples with the state carried; both give
the same numbers.

:class:`FamilyMethod` is the one constructor of the package's methods
(built from a vehicle and a :class:`~wheelload.estimators.protocol.SuspensionModel`);
methods with one flat state vector build their step with
:mod:`~wheelload.estimators.family.flat_step`.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.protocol import DEFAULT_MODEL, SuspensionModel, sample_intervals
from wheelload.estimators.result import Estimate
from wheelload.estimators.types import Sample, Signals
from wheelload.models import ModelParameters, Vehicle

PER_SAMPLE = ("u", "u_valid", "dt")
CHUNK = 20_000  # samples per call of the compiled loop


class StepMethod:
    """An :class:`~wheelload.estimators.protocol.Estimator` over one step Function.

    Subclasses set ``name`` and ``has_std`` and pass the step, the initial
    carried arrays and the fixed inputs (module docstring).
    """

    name = "compiled method"
    has_std = False

    #: Names of the per-sample inputs after ``dt`` given by :meth:`interval_inputs`.
    interval_names: tuple[str, ...] = ()

    def __init__(
        self, step: ca.Function, initial: tuple[np.ndarray, ...], fixed: tuple[np.ndarray, ...]
    ) -> None:
        self._step_function = step
        self._initial = tuple(_frozen(a) for a in initial)
        self._fixed = tuple(_frozen(a) for a in fixed)
        self._n_accum = len(initial)
        first_fixed = self._n_accum + len(PER_SAMPLE) + len(self.interval_names)
        sizes = [*self._initial, *self._fixed]
        indices = [*range(self._n_accum), *range(first_fixed, first_fixed + len(self._fixed))]
        if step.n_in() != first_fixed + len(self._fixed) or any(
            a.size != step.nnz_in(i) for a, i in zip(sizes, indices)
        ):
            raise ValueError(f"{step.name()}: state or fixed inputs of the wrong size")

    def interval_inputs(self, dt: np.ndarray) -> list[np.ndarray]:
        """Per-sample inputs that depend on the intervals ``dt`` (n,) only: arrays (n, k)."""
        return []

    def initial_state(self) -> tuple[np.ndarray, ...]:
        """The carried arrays before the first sample (read-only)."""
        return self._initial

    def step(
        self, state: tuple[np.ndarray, ...], sample: Sample, dt: float
    ) -> tuple[tuple[np.ndarray, ...], Estimate]:
        """One sample: the same Function as :meth:`run`, evaluated in Python."""
        u = sample.vector()
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = float(dt)
        extra = [a[0] for a in self.interval_inputs(np.array([dt]))]
        arguments = [*state, u, valid, dt, *extra, *self._fixed]
        shaped = [
            np.reshape(np.asarray(a, float), self._step_function.size_in(i), order="F")
            for i, a in enumerate(arguments)
        ]
        out = [np.asarray(o, float).ravel(order="F") for o in self._step_function(*shaped)]
        new_state = tuple(
            _frozen(out[i].reshape(self._initial[i].shape, order="F")) for i in range(self._n_accum)
        )
        loads, std, residual, flags = out[self._n_accum :]
        estimate = Estimate(
            t=np.array([np.nan]),
            loads=loads.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=np.array([int(round(flags[0]))], dtype=np.int64),
            has_std=self.has_std,
        )
        return new_state, estimate

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        return _compiled_loop(self._step_function, self._n_accum, self.interval_names)

    def run_loop(
        self, signals: Signals, record: tuple[int, ...] = ()
    ) -> tuple[list[np.ndarray | None], list[np.ndarray]]:
        """The compiled loop over a log in chunks of :data:`CHUNK` samples, state carried.

        Returns the history of the carried outputs in ``record`` (others None)
        and the per-sample outputs. Chunks bound the memory of the per-sample
        inputs (a 14 x 14 transition per sample for the road-angle KF).
        """
        u_all = input_matrix(signals, RateDerivativeFilter.of(self.vehicle)).T
        dt_all = sample_intervals(signals.t)
        state = list(self.initial_state())
        histories: list[list[np.ndarray]] = [[] for _ in range(self._n_accum)]
        outputs: list[list[np.ndarray]] = []
        for start in range(0, len(signals), CHUNK):
            u = u_all[start : start + CHUNK]
            valid = np.isfinite(u).astype(float)
            u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
            dt = dt_all[start : start + CHUNK]
            final, history, out = self._loop(
                state,
                list(self._fixed),
                [u, valid, dt[:, None], *self.interval_inputs(dt)],
                record=record,
            )
            state = [f.reshape(a.shape, order="F") for f, a in zip(final, self._initial)]
            for i in record:
                histories[i].append(history[i])
            outputs.append(out)
        joined = [np.concatenate(h) if i in record else None for i, h in enumerate(histories)]
        return joined, [np.concatenate(parts) for parts in zip(*outputs)]

    def run(self, signals: Signals) -> Estimate:
        """A whole log in compiled C from a fresh initial state (same numbers as ``step``)."""
        _, (loads, std, residual, flags) = self.run_loop(signals)
        return Estimate(
            t=signals.t.copy(),
            loads=loads,
            std=std,
            residual=residual,
            flags=np.rint(flags[:, 0]).astype(np.int64),
            has_std=self.has_std,
        )


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=float)
    array.flags.writeable = False
    return array


@functools.cache
def _compiled_loop(
    step: ca.Function, n_accum: int, interval_names: tuple[str, ...]
) -> CompiledLoop:
    """One compiled loop per step Function (the library itself is cached on disk)."""
    return CompiledLoop(step, n_accum, PER_SAMPLE + interval_names)


class FamilyMethod(StepMethod):
    """The one constructor of the family's methods: a vehicle and its vehicle model.

    ``Method(vehicle, suspension=...)`` reads the model parameters once and asks
    the method for its step Function (:meth:`build_step`), the carried arrays
    before the first sample (:meth:`initial_arrays`, default the static loads)
    and the fixed inputs (:meth:`fixed_arrays`, default the model parameters and
    :meth:`constants`). A method with options checks and keeps them, then calls
    this constructor.
    """

    def __init__(self, vehicle: Vehicle, *, suspension: SuspensionModel = DEFAULT_MODEL) -> None:
        self.vehicle = vehicle
        self.suspension = suspension
        self.parameters = ModelParameters.from_vehicle(vehicle)
        super().__init__(self.build_step(), self.initial_arrays(), self.fixed_arrays())

    def build_step(self) -> ca.Function:
        """The method's step Function for :attr:`vehicle` and :attr:`suspension`."""
        raise NotImplementedError

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        """The carried arrays before the first sample: by default the static loads."""
        return (np.array(self.parameters.static(), float),)

    def constants(self) -> np.ndarray:
        """The method's constant vector ``c`` (default none)."""
        return np.zeros(0)

    def fixed_arrays(self) -> tuple[np.ndarray, ...]:
        """The fixed inputs: by default the model parameters and :meth:`constants`."""
        return (self.parameters.vector(), self.constants())
