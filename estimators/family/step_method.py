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

Methods with one flat state vector ``s`` and constants ``c`` build their step
with :func:`step_symbols` and :func:`step_function`, which add the
equilibrium residual and the flags of the KF's seven update rows.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.suspension_model import (
    SuspensionModel,
    equilibrium,
    equilibrium_mask,
)
from wheelload.estimators.kernels.validity import dependency_mask, interval_is_valid, sanitise
from wheelload.estimators.kf.two_stage import Sample, sample_intervals
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import Signals
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.models import INPUTS, ModelParameters

PER_SAMPLE = ("u", "u_valid", "dt")
CHUNK = 20_000  # samples per call of the compiled loop
STEP_INPUT_NAMES = ["s", "u", "u_valid", "dt", "p", "c"]
STEP_OUTPUT_NAMES = ["s_next", "loads", "std", "residual", "flags"]


def interval_ok(dt):
    """1 where the sample interval is finite, positive and below MAX_INTERVAL."""
    return interval_is_valid(dt)


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


def used_flags(used, rejected):
    """Flags of the seven update rows' ``used`` (0 = skipped) and of a rejected interval."""
    rows = [(used[i] < 0.5, flag) for i, flag in enumerate(StepFlag.update_flags()[:7])]
    return flag_sum([*rows, (rejected, StepFlag.STEP_REJECTED)])


@dataclass(frozen=True, kw_only=True)
class StepSymbols:
    """Symbolic inputs of a flat-state step and the expressions every method needs.

    ``u`` has invalid entries replaced by 0; ``dt_ok`` is 1 for a valid
    interval and ``dt`` is then the interval (1 otherwise, never used).
    """

    s: ca.SX
    u_raw: ca.SX
    valid: ca.SX
    dt_raw: ca.SX
    p_vector: ca.SX
    p: ModelParameters
    c: ca.SX
    u: ca.SX
    dt_ok: ca.SX
    dt: ca.SX

    @property
    def d(self) -> ca.SX:
        return self.u[0:4]

    @property
    def v(self) -> ca.SX:
        return self.u[4:8]

    @property
    def acc(self) -> ca.SX:
        return self.u[8:11]

    @property
    def vx(self) -> ca.SX:
        return self.u[11]

    @property
    def rates(self) -> ca.SX:
        return self.u[12:15]

    def mask(self, outputs: ca.SX) -> ca.SX:
        """1 per output whose every needed input is valid and whose interval is valid."""
        return dependency_mask(outputs, self.u_raw, self.valid) * self.dt_ok


def step_symbols(n_state: int, n_constants: int) -> StepSymbols:
    """Fresh symbols for a step with ``n_state`` states and ``n_constants`` constants."""
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt_raw = ca.SX.sym("dt")
    p_vector, p = ModelParameters.symbolic()
    dt_ok = interval_is_valid(dt_raw)
    return StepSymbols(
        s=ca.SX.sym("s", n_state),
        u_raw=u_raw,
        valid=valid,
        dt_raw=dt_raw,
        p_vector=p_vector,
        p=p,
        c=ca.SX.sym("c", n_constants),
        u=sanitise(u_raw, valid),
        dt_ok=dt_ok,
        dt=ca.if_else(dt_ok, dt_raw, 1.0),
    )


def step_function(
    name: str, sym: StepSymbols, s_next, loads, std, used_suspension, equilibrium
) -> ca.Function:
    """A flat-state method's step Function in the runner's layout (module docstring).

    ``equilibrium``: ``(A, b, mask)`` of the equilibrium the residual
    :math:`b - A \\hat x` is reported against (``mask`` 1 per row whose inputs
    are valid; a row that cannot be formed is reported as 0 and flagged). A
    rejected interval holds the state (``s_next = s``).
    """
    A, b, mask = equilibrium
    mask_c = mask * sym.dt_ok
    residual = (b - ca.mtimes(A, loads)) * mask_c
    s_next = ca.if_else(sym.dt_ok, s_next, sym.s)
    used = ca.vertcat(used_suspension, mask_c)
    flags = used_flags(used, 1 - sym.dt_ok)
    return ca.Function(
        name,
        [sym.s, sym.u_raw, sym.valid, sym.dt_raw, sym.p_vector, sym.c],
        [s_next, loads, std, residual, flags],
        STEP_INPUT_NAMES,
        STEP_OUTPUT_NAMES,
    )


def hold(valid, new, old):
    """``new`` where ``valid`` else ``old`` (elementwise; no arithmetic on ``new`` when invalid)."""
    return ca.vertcat(*[ca.if_else(valid[i], new[i], old[i]) for i in range(new.shape[0])])


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
        u_all = input_matrix(signals).T
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


def step_name(base: str, model: SuspensionModel) -> str:
    """The step Function's name: ``base`` for the full model, ``base_paper`` for the paper's."""
    return base if model is SuspensionModel.FULL else f"{base}_paper"


def model_equilibrium(model: SuspensionModel, sym: StepSymbols):
    """``(A, b, mask)`` of ``model``'s equilibrium for :func:`step_function`."""
    A, b = equilibrium(model, sym.u, sym.valid, sym.p_vector)
    return A, b, equilibrium_mask(sym.u_raw, sym.valid, sym.p_vector)
