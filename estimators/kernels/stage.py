"""A stage of a symbolic step: a named CasADi Function of symbols shaped like its arguments,
called on them.

A step built of stages is one expression graph: an SX Function called on SX arguments is
evaluated symbolically (its operations replayed on the arguments), so the composed step, its
Jacobians and the C emitted from it are those of the expressions written out in one piece;
each stage is still a Function of its own, named ``<prefix>_<stage>``, to evaluate, test or
emit alone (CasADi, "Function call on SX": inlined).

Example
-------
>>> def scaled(x, k):
...     return {"y": k * x}
>>> values = {"x": ca.SX.sym("x", 2), "k": ca.SX.sym("k")}
>>> out, function = stage("wheelload_kf", scaled, values)
>>> function.name()
'wheelload_kf_scaled'
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping

import casadi as ca


def stage_name(build: Callable[..., dict]) -> str:
    """A stage builder's name (of the function a ``functools.partial`` wraps), less a
    leading ``_``."""
    return getattr(build, "func", build).__name__.lstrip("_")


def stage(
    prefix: str, build: Callable[..., dict], values: Mapping, *, as_function: bool = True
) -> tuple[dict, ca.Function | None]:
    """``build``'s outputs on ``values`` (by name) and the Function ``<prefix>_<name>`` they
    come from; ``build``'s arguments without a default are read from ``values`` by name and
    its name (less a leading ``_``) names the stage. ``as_function`` False: ``build`` is
    called on the values themselves (no Function, None returned)."""
    names = [
        name
        for name, parameter in inspect.signature(build).parameters.items()
        if parameter.default is inspect.Parameter.empty
    ]
    if not as_function:
        return build(**{name: values[name] for name in names}), None
    arguments = [ca.SX(values[name]) for name in names]
    symbols = [ca.SX.sym(name, value.sparsity()) for name, value in zip(names, arguments)]
    outputs = build(**dict(zip(names, symbols)))
    function = ca.Function(
        f"{prefix}_{stage_name(build)}",
        symbols,
        [ca.SX(value) for value in outputs.values()],
        names,
        list(outputs),
    )
    return dict(zip(outputs, function.call(arguments))), function
