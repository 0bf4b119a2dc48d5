"""The filter step as a composition of named stage Functions (estimators/kf/step.py)."""

import casadi as ca

from wheelload.estimators.kf.step import (
    INLINE_STAGES,
    STAGE_PREFIX,
    step_composition,
    step_function,
)
from wheelload.estimators.kf.step_cache import STEP_OUTPUT_NAMES
from wheelload.models import equilibrium_function, suspension_function

STAGES = (
    "interval", "payload", "plausibility", "model", "monitor", "masks", "noise", "predict",
    "gate", "suspension_update", "equilibrium_update", "roll_split", "limits",
    "payload_update", "sigma", "monitor_next", "outputs",
)  # fmt: skip


def test_every_stage_is_a_named_function_but_the_inline_ones():
    inputs, values, functions = step_composition(suspension_function(), equilibrium_function())
    assert tuple(functions) == STAGES
    for name, function in functions.items():
        if name in INLINE_STAGES:
            assert function is None
        else:
            assert function.name() == f"{STAGE_PREFIX}_{name}"
            assert not function.has_free()
    assert set(STEP_OUTPUT_NAMES) <= set(values)
    assert list(inputs) == ["x", "P", "m", "u_raw", "valid_raw", "dt", "p_file", "tuning"]


def test_the_composed_step_is_one_expression_graph():
    """The stages' calls are inlined: the step Function holds only scalar operations (no call
    of a stage Function), the same instruction count as its expressions written out."""
    step = step_function()
    inputs, outputs = step.sx_in(), step.call(step.sx_in())
    again = ca.Function("again", inputs, ca.cse(outputs))
    assert step.n_instructions() == again.n_instructions()
    assert all(step.instruction_id(k) != ca.OP_CALL for k in range(step.n_instructions()))
