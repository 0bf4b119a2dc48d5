"""The default filter step Function kept on disk between runs, and its inputs and outputs.

Building :func:`~wheelload.estimators.kf.step.step_function` (the models'
expressions, Jacobians, guards, common subexpressions) takes about 0.2 s of
every ``wheelload estimate``; loading its serialised form takes about 10 ms.
It is stored as any model Function
(:func:`~wheelload.models.runtime.function_cache.stored_function`: named by a hash
of every ``.py`` file of ``wheelload.models`` and ``wheelload.estimators`` and of
the CasADi version, so an edit of any of them builds it again); a warm estimate
runs its stored column loop and imports neither the step's module nor the models
(:data:`STEP_FUNCTION` names the builder; the names of the step's inputs and outputs,
which its callers read, are here).

Example
-------
>>> step = default_step_function()  # the same Function as step_function()
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.runtime.function_cache import Builder, stored_function

#: The step Function's name (and its C symbol).
STEP_NAME = "wheelload_kf_step"
STEP_INPUT_NAMES = ["x", "P", "m", "u", "u_valid", "dt", "p", "tuning"]
STEP_OUTPUT_NAMES = [
    "x_next", "P_next", "m_next", "std", "residual", "used", "z", "innovation",
    "innovation_variance", "status", "fault_statistic", "fault", "mass_properties",
    "mass_properties_std",
]  # fmt: skip
#: The step's carried state: x, P and the monitor m.
N_CARRIED = 3
#: The seven update rows in update order (innovation outputs).
UPDATE_ROWS = (
    "suspension_fl", "suspension_fr", "suspension_rl", "suspension_rr",
    "vertical", "pitch", "roll",
)  # fmt: skip
#: :func:`~wheelload.estimators.kf.step.step_function` with its defaults, by name.
STEP_FUNCTION = Builder("wheelload.estimators.kf.step", "step_function")


def default_step_function() -> ca.Function:
    """:func:`~wheelload.estimators.kf.step.step_function` with its defaults, loaded from
    the build folder when this code built it before (module docstring)."""
    return stored_function(STEP_FUNCTION)
