"""A stage: a named Function of symbols shaped like its arguments, called on them (inlined)."""

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.kernels.stage import stage, stage_name


def _scaled(x, k, *, offset):
    return {"y": k * x + offset, "total": ca.sum1(x)}


def test_a_stage_is_a_named_function_whose_call_inlines():
    """The stage's outputs on SX arguments are the expressions built directly (same Function
    when composed); evaluated alone, the Function gives the same numbers (to 1e-15: one
    rounding of the same operations)."""
    x, k = ca.SX.sym("a", 3), ca.SX.sym("b")
    build = functools.partial(_scaled, offset=2.0)
    outputs, function = stage("wheelload_kf", build, {"x": x, "k": k, "unused": ca.SX.sym("c")})
    assert function.name() == "wheelload_kf_scaled" and stage_name(build) == "scaled"
    assert function.name_in() == ["x", "k"] and function.name_out() == ["y", "total"]
    direct = _scaled(x, k, offset=2.0)
    composed = ca.Function("f", [x, k], [outputs["y"], outputs["total"]])
    built = ca.Function("f", [x, k], [direct["y"], direct["total"]])
    assert composed.serialize() == built.serialize()
    y, total = function(np.array([1.0, 2.0, 3.0]), 0.5)
    np.testing.assert_allclose(np.asarray(y).ravel(), [2.5, 3.0, 3.5], rtol=1e-15)
    assert float(total) == 6.0


def test_an_inline_stage_is_called_on_the_values():
    x = ca.SX.sym("a", 2)
    outputs, function = stage(
        "p", functools.partial(_scaled, offset=0.0), {"x": x, "k": 2.0}, as_function=False
    )
    assert function is None
    assert ca.is_equal(outputs["total"], ca.sum1(x), 1)  # the same sum (structurally)
