r"""The residual :math:`b - A \hat x` and update flags of a family step on one flat state ``s``.

Building blocks of a step with one flat state vector ``s`` and constants ``c``:
the symbols of the runner's layout (:mod:`~wheelload.estimators.family.step_method`)
with the inputs sanitised and the interval checked (:func:`step_symbols`), and
the step Function (:func:`step_function`) that adds the residual of the
method's loads against the equilibrium and the flags of the KF's seven update
rows (:class:`~wheelload.estimators.result.StepFlag`).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from wheelload.estimators.family.suspension_model import equilibrium, equilibrium_mask
from wheelload.estimators.protocol import SuspensionModel
from wheelload.estimators.result import StepFlag
from wheelload.models import INPUTS, ModelParameters
from wheelload.models.input_validity import dependency_mask, interval_is_valid, sanitise

STEP_INPUT_NAMES = ["s", "u", "u_valid", "dt", "p", "c"]
STEP_OUTPUT_NAMES = ["s_next", "loads", "std", "residual", "flags"]


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
    base: str,
    model: SuspensionModel,
    sym: StepSymbols,
    s_next,
    loads,
    std,
    used_suspension,
    equilibrium=None,
) -> ca.Function:
    """A flat-state method's step Function in the runner's layout, named by :func:`step_name`.

    ``equilibrium``: ``(A, b, mask)`` of the equilibrium the residual
    :math:`b - A \\hat x` is reported against (``mask`` 1 per row whose inputs
    are valid; a row that cannot be formed is reported as 0 and flagged);
    default ``model``'s (:func:`model_equilibrium`). A rejected interval holds
    the state (``s_next = s``).
    """
    if equilibrium is None:
        equilibrium = model_equilibrium(model, sym)
    A, b, mask = equilibrium
    mask_c = mask * sym.dt_ok
    residual = (b - ca.mtimes(A, loads)) * mask_c
    s_next = ca.if_else(sym.dt_ok, s_next, sym.s)
    used = ca.vertcat(used_suspension, mask_c)
    flags = used_flags(used, 1 - sym.dt_ok)
    return ca.Function(
        step_name(base, model),
        [sym.s, sym.u_raw, sym.valid, sym.dt_raw, sym.p_vector, sym.c],
        [s_next, loads, std, residual, flags],
        STEP_INPUT_NAMES,
        STEP_OUTPUT_NAMES,
    )


def hold(valid, new, old):
    """``new`` where ``valid`` else ``old`` (elementwise; no arithmetic on ``new`` when invalid)."""
    return ca.vertcat(*[ca.if_else(valid[i], new[i], old[i]) for i in range(new.shape[0])])


def step_name(base: str, model: SuspensionModel) -> str:
    """The step Function's name: ``base`` for the full model, ``base_paper`` for the paper's."""
    return base if model is SuspensionModel.FULL else f"{base}_paper"


def model_equilibrium(model: SuspensionModel, sym: StepSymbols):
    """``(A, b, mask)`` of ``model``'s equilibrium for :func:`step_function`."""
    A, b = equilibrium(model, sym.u, sym.valid, sym.p_vector)
    return A, b, equilibrium_mask(sym.u_raw, sym.valid, sym.p_vector)
