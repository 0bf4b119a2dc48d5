"""Shared runner of the methods whose per-sample step is one CasADi Function.

The step Function takes the carried state first (``n_accum`` inputs, returned
as the first ``n_accum`` outputs), then the per-sample inputs ``u`` (the
:data:`INPUTS` below), ``u_valid`` (1 where the input is finite) and ``dt``,
then any further per-sample inputs that depend on the interval alone (e.g. a
transition matrix, from :meth:`CompiledMethod.interval_inputs`), then fixed
parameter vectors. After the carried state it returns ``loads``
(4), ``std`` (4), ``residual`` (3) and ``flags`` (1, a sum of
:class:`~wheelload.estimators.result.StepFlag` values). :meth:`step` calls the
Function once; :meth:`run` loops it in compiled C
(:class:`~wheelload.estimators.compiled.CompiledLoop`); both give the same
numbers.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.compiled import CompiledLoop
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import MAX_INTERVAL, Sample, sample_intervals

#: Order of the per-sample input vector ``u``.
INPUTS = (
    "d_fl", "d_fr", "d_rl", "d_rr",
    "v_fl", "v_fr", "v_rl", "v_rr",
    "ax", "ay", "az", "vx", "wx", "wy", "wz",
)  # fmt: skip
PER_SAMPLE = ("u", "u_valid", "dt")
CHUNK = 20_000  # samples per call of the compiled loop


def sanitise(u: ca.SX, valid: ca.SX) -> ca.SX:
    """Invalid inputs replaced by zero, so that no NaN or Inf enters the arithmetic."""
    return ca.vertcat(*[ca.if_else(valid[i], u[i], 0) for i in range(u.shape[0])])


def interval_ok(dt):
    """1 where the sample interval is finite, positive and below MAX_INTERVAL."""
    return ca.logic_and(dt > 0, dt < MAX_INTERVAL)


def flag_sum(conditions: list[tuple[object, StepFlag]]):
    """Sum of the flag values whose condition (an SX 0/1) is set."""
    total = 0
    for condition, flag in conditions:
        total = total + condition * float(flag.value)
    return total


def step_flags(wheel_skipped, equilibrium_skipped, rejected):
    """Status of a family step: the four wheels' skips, the three equilibrium rows, rejection.

    ``wheel_skipped``: four 0/1 conditions (FL, FR, RL, RR); the others single conditions.
    """
    wheels = list(zip(wheel_skipped, StepFlag.update_flags()[:4]))
    rows = [(equilibrium_skipped, flag) for flag in StepFlag.update_flags()[4:7]]
    return flag_sum([*wheels, *rows, (rejected, StepFlag.STEP_REJECTED)])


def input_vector(sample: Sample) -> np.ndarray:
    """A sample in :data:`INPUTS` order; rates NaN when the sample has none."""
    rates = np.full(3, np.nan) if sample.rates is None else np.asarray(sample.rates, float)
    return np.concatenate([sample.d, sample.v, sample.acc, [sample.vx], rates]).astype(float)


def input_matrix(signals: Signals) -> np.ndarray:
    """The inputs of a log in :data:`INPUTS` order, shape (n, 15)."""
    rates = np.full((len(signals), 3), np.nan) if signals.rates is None else signals.rates
    return np.column_stack([signals.d, signals.v, signals.acc, signals.vx, rates]).astype(float)


class CompiledMethod:
    """An estimator made of a CasADi step Function (see module docstring).

    Subclasses set ``name``, ``has_std`` and call ``super().__init__`` with the
    step, the initial state and the fixed inputs.
    """

    name = "compiled method"
    has_std = False

    #: Names of the per-sample inputs after ``dt`` given by :meth:`interval_inputs`.
    interval_names: tuple[str, ...] = ()

    def __init__(
        self, step: ca.Function, initial: tuple[np.ndarray, ...], fixed: tuple[np.ndarray, ...]
    ) -> None:
        self._step_function = step
        self._initial = tuple(np.asarray(a, float) for a in initial)
        self._fixed = tuple(np.asarray(a, float) for a in fixed)
        self._n_accum = len(initial)

    def interval_inputs(self, dt: np.ndarray) -> list[np.ndarray]:
        """Per-sample inputs that depend on the intervals ``dt`` (n,) only: arrays (n, k)."""
        return []

    def initial_state(self) -> tuple[np.ndarray, ...]:
        """The carried arrays before the first sample (copies; never mutated)."""
        return tuple(a.copy() for a in self._initial)

    def step(
        self, state: tuple[np.ndarray, ...], sample: Sample, dt: float
    ) -> tuple[tuple[np.ndarray, ...], Estimate]:
        """One sample: the new state and a one-row estimate."""
        u = input_vector(sample)
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = float(dt) if np.isfinite(dt) else -1.0
        extra = [a[0] for a in self.interval_inputs(np.array([dt]))]
        arguments = [*state, u, valid, dt, *extra, *self._fixed]
        shaped = [
            np.reshape(np.asarray(a, float), self._step_function.size_in(i), order="F")
            for i, a in enumerate(arguments)
        ]
        out = self._step_function(*shaped)
        out = [np.asarray(o, float).ravel(order="F") for o in out]
        shapes = [self._initial[i].shape for i in range(self._n_accum)]
        new_state = tuple(out[i].reshape(shapes[i], order="F") for i in range(self._n_accum))
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
        return CompiledLoop(self._step_function, self._n_accum, PER_SAMPLE + self.interval_names)

    def run_loop(
        self, signals: Signals, record: tuple[int, ...] = ()
    ) -> tuple[list[np.ndarray | None], list[np.ndarray]]:
        """The compiled loop over a log in chunks of :data:`CHUNK` samples, state carried.

        Returns the history of the carried outputs in ``record`` (others None)
        and the per-sample outputs. Chunks bound the memory of the per-sample
        inputs (a 14 x 14 transition per sample for the road-angle KF).
        """
        u_all = input_matrix(signals)
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
        """A whole log in compiled code from a fresh initial state (same numbers as ``step``)."""
        _, (loads, std, residual, flags) = self.run_loop(signals)
        return Estimate(
            t=signals.t.copy(),
            loads=loads,
            std=std,
            residual=residual,
            flags=np.rint(flags[:, 0]).astype(np.int64),
            has_std=self.has_std,
        )
