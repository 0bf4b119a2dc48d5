"""Runner of the B-F methods: one masked CasADi step over a flat state, looped in C.

Every method of this package is one CasADi Function

``step(s, u, u_valid, dt, p, c) -> (s_next, loads, std, residual, used)``

with a flat state vector ``s``, the per-sample inputs ``u`` in
:data:`FAMILY_INPUTS` order (the two-stage KF's inputs plus the body rates),
their validity, the interval, the model parameters ``p``
(:class:`~wheelload.models.ModelParameters`) and the method's constants ``c``.
``used`` has the seven entries of the KF's (suspension FL..RR, vertical,
pitch, roll): 0 marks an update skipped for a missing input (or, for the
last three, a residual row that could not be formed and is reported as 0).
:meth:`StepMethod.run` loops the step in generated C
(:class:`~wheelload.estimators.compiled.CompiledLoop`, as the KF);
:meth:`StepMethod.step` calls the same Function, so the two agree to
rounding.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.compiled import CompiledLoop
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals
from wheelload.estimators.two_stage import (
    INPUTS,
    MAX_INTERVAL,
    Sample,
    _dependency_mask,
    _sanitise,
    flags_from_used,
    input_matrix,
    interval_is_valid,
    sample_intervals,
)
from wheelload.models import ModelParameters, paper_equilibrium_function

#: Per-sample inputs of the family's steps: the KF's, then the body rates [rad/s].
FAMILY_INPUTS = (*INPUTS, "wx", "wy", "wz")
STEP_INPUT_NAMES = ["s", "u", "u_valid", "dt", "p", "c"]
STEP_OUTPUT_NAMES = ["s_next", "loads", "std", "residual", "used"]


@dataclass(frozen=True, kw_only=True)
class StepSymbols:
    """Symbolic inputs of a step and the expressions every method needs.

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
        return _dependency_mask(outputs, self.u_raw, self.valid) * self.dt_ok


def step_symbols(n_state: int, n_constants: int) -> StepSymbols:
    """Fresh symbols for a step with ``n_state`` states and ``n_constants`` constants."""
    u_raw = ca.SX.sym("u", len(FAMILY_INPUTS))
    valid = ca.SX.sym("u_valid", len(FAMILY_INPUTS))
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
        u=_sanitise(u_raw, valid),
        dt_ok=dt_ok,
        dt=ca.if_else(dt_ok, dt_raw, 1.0),
    )


def step_function(name: str, sym: StepSymbols, s_next, loads, std, used_suspension) -> ca.Function:
    """The method's step Function; residual and its row mask from the equilibrium model.

    A rejected interval holds the state (``s_next = s``).
    """
    A, b = paper_equilibrium_function()(sym.acc, sym.vx, sym.p_vector)
    mask_c = sym.mask(b)
    residual = (b - ca.mtimes(A, loads)) * mask_c
    s_next = ca.if_else(sym.dt_ok, s_next, sym.s)
    used = ca.vertcat(used_suspension, mask_c)
    return ca.Function(
        name,
        [sym.s, sym.u_raw, sym.valid, sym.dt_raw, sym.p_vector, sym.c],
        [s_next, loads, std, residual, used],
        STEP_INPUT_NAMES,
        STEP_OUTPUT_NAMES,
    )


def hold(valid, new, old):
    """``new`` where ``valid`` else ``old`` (elementwise; no arithmetic on ``new`` when invalid)."""
    return ca.vertcat(*[ca.if_else(valid[i], new[i], old[i]) for i in range(new.shape[0])])


def family_input_matrix(signals: Signals) -> np.ndarray:
    """Per-sample inputs in :data:`FAMILY_INPUTS` order, shape (n, 15); NaN rates if not logged."""
    rates = np.full((len(signals), 3), np.nan) if signals.rates is None else signals.rates
    return np.hstack([input_matrix(signals).T, rates])


def sample_vector(sample: Sample) -> np.ndarray:
    """One sample in :data:`FAMILY_INPUTS` order."""
    rates = np.full(3, np.nan) if sample.rates is None else np.asarray(sample.rates, float)
    return np.concatenate([sample.vector(), rates])


@dataclass(frozen=True)
class MethodState:
    """The flat state vector of a compiled method (read-only)."""

    s: np.ndarray


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=float)
    array.flags.writeable = False
    return array


def _flags(used: np.ndarray, dt: np.ndarray) -> np.ndarray:
    flags = flags_from_used(used)
    rejected = ~((dt > 0.0) & (dt < MAX_INTERVAL))
    return np.where(rejected, flags | int(StepFlag.STEP_REJECTED), flags).astype(np.int64)


class StepMethod:
    """An :class:`~wheelload.estimators.protocol.Estimator` over one step Function.

    Subclasses set ``name`` and ``has_std`` and pass the step, the model
    parameters, the method's constants and the initial state vector.
    """

    name = "compiled method"
    has_std = False

    def __init__(
        self, step: ca.Function, p: np.ndarray, constants: np.ndarray, initial: np.ndarray
    ) -> None:
        self._step = step
        self.p = _frozen(p)
        self.constants = _frozen(constants)
        self._initial = _frozen(initial)
        if self._initial.size != step.nnz_in(0) or self.constants.size != step.nnz_in(5):
            raise ValueError(f"{step.name()}: state or constants of the wrong size")

    def initial_state(self) -> MethodState:
        return MethodState(self._initial)

    def step(self, state: MethodState, sample: Sample, dt: float) -> tuple[MethodState, Estimate]:
        """One sample: the same Function as :meth:`run`, evaluated in Python."""
        u = sample_vector(sample)
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        out = self._step(state.s, u, valid, float(dt), self.p, self.constants)
        s, loads, std, residual, used = (np.asarray(o, float).ravel() for o in out)
        estimate = Estimate(
            t=np.array([np.nan]),
            loads=loads.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=_flags(used.reshape(7, 1), np.array([float(dt)])),
            has_std=self.has_std,
        )
        return MethodState(_frozen(s)), estimate

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        return _compiled_loop(self._step)

    def run(self, signals: Signals) -> Estimate:
        """The whole log in compiled C from a fresh initial state."""
        u = family_input_matrix(signals)
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = sample_intervals(signals.t)
        _, _, (loads, std, residual, used) = self._loop(
            [self._initial], [self.p, self.constants], [u, valid, dt[:, None]]
        )
        return Estimate(
            t=signals.t.copy(),
            loads=loads,
            std=std,
            residual=residual,
            flags=_flags(used.T, dt),
            has_std=self.has_std,
        )


@functools.cache
def _compiled_loop(step: ca.Function) -> CompiledLoop:
    """One compiled loop per step Function (the library itself is cached on disk)."""
    return CompiledLoop(step, 1, ("u", "u_valid", "dt"))
