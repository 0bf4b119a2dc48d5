"""Straight-line C from a CasADi SX Function, in double or true single precision.

CasADi's own code generator writes ``double`` literals and helper functions
that a single-precision build cannot take under ``-Wdouble-promotion
-Wconversion``. This emitter walks the Function's algorithm instead
(``instruction_id``, ``instruction_input``, ``instruction_output``,
``instruction_constant``) and prints one C statement per instruction on
local work variables of a ``real`` typedef, with ``f``-suffixed literals and
``sqrtf``-style maths functions in single precision; ``fmin``/``fmax`` are
written as selects.

Selects are written in the forms gcc compiles without a branch (a compare
and a blend, or a ``min``/``max`` instruction): the emitter knows which work
variables hold a truth value (exactly 0 or 1: comparisons, logic, products
of truth values, the inputs named in ``boolean_inputs``) and which can never
be NaN (constants, truth values, ``fmax`` with such an operand), and writes
``c ? x : 0`` as ``c > 0.5``, ``and``/``or`` and products of truth values as
``min``/``max``, ``not`` as ``1 - c``, and ``fmax(a, b)`` with a non-NaN
``b`` as one compare. Each form gives the value of the C99 one for every
operand value, NaN included, so the emitted code computes the same numbers
(a ``boolean_inputs`` value of -0.0 may come out as +0.0 or the reverse).

Example
-------
>>> body = emit_statements(f, ["x[{}]", "u[{}]"], ["y[{}]"], Precision.FLOAT, "wl_real")
"""

from __future__ import annotations

import collections
import enum
import math
from collections.abc import Sequence

import casadi as ca
import numpy as np


class Precision(enum.Enum):
    """Floating-point type of the generated code."""

    DOUBLE = "double"
    FLOAT = "float"


class EmitError(ValueError):
    """The Function holds an operation or a constant that has no C form here."""


def literal(value: float, precision: Precision) -> str:
    """A C floating literal of ``value`` in ``precision`` (shortest round-trip digits)."""
    if not math.isfinite(value):
        raise EmitError(f"constant {value!r} has no finite C literal")
    if precision is Precision.FLOAT:
        text = str(np.float32(value))
    else:
        text = repr(float(value))
    if not any(mark in text for mark in ".en"):
        text += ".0"
    return text + ("f" if precision is Precision.FLOAT else "")


# Unary and binary operations: C expression templates on operands {0}, {1};
# {f} is the maths-function suffix ("" for double, "f" for float), {one} and
# {zero} the literals 1 and 0 of the precision.
_TEMPLATES = {
    ca.OP_ASSIGN: "{0}",
    ca.OP_ADD: "{0} + {1}",
    ca.OP_SUB: "{0} - {1}",
    ca.OP_MUL: "{0} * {1}",
    ca.OP_DIV: "{0} / {1}",
    ca.OP_NEG: "-{0}",
    ca.OP_SQ: "{0} * {0}",
    ca.OP_TWICE: "{0} + {0}",
    ca.OP_INV: "{one} / {0}",
    ca.OP_SQRT: "sqrt{f}({0})",
    ca.OP_EXP: "exp{f}({0})",
    ca.OP_LOG: "log{f}({0})",
    ca.OP_POW: "pow{f}({0}, {1})",
    ca.OP_CONSTPOW: "pow{f}({0}, {1})",
    ca.OP_SIN: "sin{f}({0})",
    ca.OP_COS: "cos{f}({0})",
    ca.OP_TAN: "tan{f}({0})",
    ca.OP_ASIN: "asin{f}({0})",
    ca.OP_ACOS: "acos{f}({0})",
    ca.OP_ATAN: "atan{f}({0})",
    ca.OP_ATAN2: "atan2{f}({0}, {1})",
    ca.OP_SINH: "sinh{f}({0})",
    ca.OP_COSH: "cosh{f}({0})",
    ca.OP_TANH: "tanh{f}({0})",
    ca.OP_FLOOR: "floor{f}({0})",
    ca.OP_CEIL: "ceil{f}({0})",
    ca.OP_FMOD: "fmod{f}({0}, {1})",
    ca.OP_FABS: "fabs{f}({0})",
    # fmin/fmax as selects (a NaN operand loses, as in C99 fmin/fmax): no branch or
    # library call, so that gcc can vectorise the step across filter instances.
    ca.OP_FMIN: "({1} != {1}) ? {0} : (({0} < {1}) ? {0} : {1})",
    ca.OP_FMAX: "({1} != {1}) ? {0} : (({0} > {1}) ? {0} : {1})",
    ca.OP_COPYSIGN: "copysign{f}({0}, {1})",
    ca.OP_ERF: "erf{f}({0})",
    ca.OP_HYPOT: "hypot{f}({0}, {1})",
    ca.OP_SIGN: "({0} > {zero}) ? {one} : (({0} < {zero}) ? -{one} : {zero})",
    ca.OP_LT: "({0} < {1}) ? {one} : {zero}",
    ca.OP_LE: "({0} <= {1}) ? {one} : {zero}",
    ca.OP_EQ: "({0} == {1}) ? {one} : {zero}",
    ca.OP_NE: "({0} != {1}) ? {one} : {zero}",
    ca.OP_NOT: "({0} == {zero}) ? {one} : {zero}",
    # Logic as nested selects (no short-circuit): vectorisable.
    ca.OP_AND: "({0} != {zero}) ? (({1} != {zero}) ? {one} : {zero}) : {zero}",
    ca.OP_OR: "({0} != {zero}) ? {one} : (({1} != {zero}) ? {one} : {zero})",
    ca.OP_IF_ELSE_ZERO: "({0} != {zero}) ? {1} : {zero}",
}

#: Operations that are floating-point arithmetic (counted as FLOPs); the rest
#: are data movement, selects and comparisons.
ARITHMETIC = frozenset(
    op
    for op in _TEMPLATES
    if op not in (ca.OP_ASSIGN, ca.OP_IF_ELSE_ZERO, ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE,
                  ca.OP_NOT, ca.OP_AND, ca.OP_OR, ca.OP_SIGN)
)  # fmt: skip

OPERATION_NAMES = {
    getattr(ca, name): name[3:].lower() for name in dir(ca) if name.startswith("OP_")
}


def operation_counts(f: ca.Function) -> collections.Counter[str]:
    """How many instructions of each operation (``add``, ``mul``, ...) ``f`` executes."""
    return collections.Counter(
        OPERATION_NAMES[f.instruction_id(k)] for k in range(f.n_instructions())
    )


def flop_count(f: ca.Function) -> int:
    """Floating-point operations per evaluation of ``f`` (one per arithmetic instruction)."""
    return sum(1 for k in range(f.n_instructions()) if f.instruction_id(k) in ARITHMETIC)


#: Latency [cycles] of each operation on one scalar, for the dependency-chain
#: bound: add/sub/mul/FMA 3-4, divide 13, square root 15-20 on current x86-64
#: cores (AMD Zen 4, Intel Golden Cove; Agner Fog's instruction tables); a
#: compare and blend (selects, logic) 2; sign and abs 1; moves 0.
LATENCY = {
    **dict.fromkeys((ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_SQ, ca.OP_TWICE), 3),
    **dict.fromkeys((ca.OP_DIV, ca.OP_INV), 13),
    ca.OP_SQRT: 15,
    **dict.fromkeys((ca.OP_NEG, ca.OP_FABS, ca.OP_COPYSIGN), 1),
    **dict.fromkeys(
        (ca.OP_FMIN, ca.OP_FMAX, ca.OP_IF_ELSE_ZERO, ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE,
         ca.OP_NOT, ca.OP_AND, ca.OP_OR, ca.OP_SIGN),
        2,
    ),
    **dict.fromkeys((ca.OP_ASSIGN, ca.OP_INPUT, ca.OP_CONST, ca.OP_OUTPUT), 0),
}  # fmt: skip
#: Latency assumed for an operation not in :data:`LATENCY` (maths library calls).
CALL_LATENCY = 40


def critical_path(f: ca.Function, latency: dict[int, int] | None = None) -> int:
    """Cycles of the longest dependency chain through ``f``'s instructions.

    Each instruction starts when its operands are ready and takes its
    :data:`LATENCY`; with unlimited issue width this is the fastest any core
    can evaluate ``f`` once: the dependency-chain bound of the step.
    """
    latency = LATENCY if latency is None else latency
    ready: dict[int, int] = {}
    longest = 0
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op == ca.OP_OUTPUT:
            (work,) = f.instruction_input(k)
            longest = max(longest, ready.get(work, 0))
            continue
        (target,) = f.instruction_output(k)
        if op in (ca.OP_INPUT, ca.OP_CONST):
            ready[target] = 0
            continue
        start = max((ready.get(w, 0) for w in f.instruction_input(k) if w >= 0), default=0)
        ready[target] = start + latency.get(op, CALL_LATENCY)
    return longest


def _element(names: str | Sequence[str], nz: int) -> str:
    return names.format(nz) if isinstance(names, str) else names[nz]


#: Operations whose result is a truth value, exactly 0 or 1.
_TRUTH = frozenset(
    (ca.OP_LT, ca.OP_LE, ca.OP_EQ, ca.OP_NE, ca.OP_NOT, ca.OP_AND, ca.OP_OR)
)  # fmt: skip
#: Operations whose result is not NaN when their (first) operand is not.
_KEEPS_NUMBER = frozenset((ca.OP_ASSIGN, ca.OP_FABS, ca.OP_NEG, ca.OP_SQ))


class _Values:
    """What is known of each work variable: a truth value (0 or 1), never NaN, a constant."""

    def __init__(self) -> None:
        self.truth: set[int] = set()
        self.number: set[int] = set()
        self.constant: dict[int, float] = {}

    def define(self, target: int, *, truth: bool, number: bool, constant: float | None) -> None:
        for known, holds in ((self.truth, truth), (self.number, number)):
            if holds:
                known.add(target)
            else:
                known.discard(target)
        if constant is None:
            self.constant.pop(target, None)
        else:
            self.constant[target] = constant

    def after(self, op: int, operands: list[int]) -> tuple[bool, bool]:
        """(truth value, never NaN) of the result of ``op`` on ``operands``."""
        truths = [w in self.truth for w in operands]
        numbers = [w in self.number for w in operands]
        truth = (
            op in _TRUTH
            or (op in (ca.OP_MUL, ca.OP_FMIN, ca.OP_FMAX) and all(truths))
            or (op in (ca.OP_ASSIGN, ca.OP_SQ) and truths[0])
            or (op == ca.OP_SUB and self.constant.get(operands[0]) == 1.0 and truths[1])
            or (op == ca.OP_IF_ELSE_ZERO and truths[1])
        )
        number = (
            truth
            or (op in (ca.OP_FMIN, ca.OP_FMAX) and any(numbers))
            or (op in _KEEPS_NUMBER and numbers[0])
            or (op == ca.OP_IF_ELSE_ZERO and numbers[1])
        )
        return truth, number


def _select(op: int, operands: list[int], values: _Values, precision: Precision) -> str | None:
    """Branch-free C of a select or logic operation, or None for :data:`_TEMPLATES`' form.

    The forms equal the C99 ones for every operand value: ``c != 0`` and
    ``c > 0.5`` agree on truth values; ``min``/``max`` of truth values are
    their ``and``/``or``; ``(b == b) ? max : a`` is ``fmax``'s NaN rule.
    """
    one, zero, half = (literal(v, precision) for v in (1.0, 0.0, 0.5))
    suffix = "f" if precision is Precision.FLOAT else ""
    a, b = (f"w{w}" for w in (*operands, operands[0])[:2])

    def truth(w: int) -> str:
        # C's (v != 0) as a compare against |v| (NaN counts as true, as in C).
        return (
            f"w{w}" if w in values.truth else f"((fabs{suffix}(w{w}) <= {zero}) ? {zero} : {one})"
        )

    if op == ca.OP_IF_ELSE_ZERO:
        if operands[0] in values.truth:
            return f"({a} > {half}) ? {b} : {zero}"
        return f"(fabs{suffix}({a}) <= {zero}) ? {zero} : {b}"
    if op == ca.OP_NOT:
        if operands[0] in values.truth:
            return f"{one} - {a}"
        return f"(fabs{suffix}({a}) <= {zero}) ? {one} : {zero}"
    if op == ca.OP_MUL and all(w in values.truth for w in operands):
        return f"({a} < {b}) ? {a} : {b}"  # a product of truth values is their minimum
    if op in (ca.OP_AND, ca.OP_OR):
        left, right = truth(operands[0]), truth(operands[1])
        compare = "<" if op == ca.OP_AND else ">"
        return f"({left} {compare} {right}) ? {left} : {right}"
    if op in (ca.OP_FMIN, ca.OP_FMAX):
        compare = "<" if op == ca.OP_FMIN else ">"
        pick = f"({a} {compare} {b}) ? {a} : {b}"
        return pick if operands[1] in values.number else f"({b} == {b}) ? ({pick}) : {a}"
    return None


def emit_statements(
    f: ca.Function,
    inputs: Sequence[str | Sequence[str]],
    outputs: Sequence[str | Sequence[str]],
    precision: Precision,
    real: str,
    *,
    boolean_inputs: Sequence[int] = (),
    branch_free: bool = True,
) -> str:
    """C statements that evaluate the SX Function ``f``.

    Parameters
    ----------
    f
        An SX Function.
    inputs, outputs
        Per input and output of ``f``, the C expression (inputs) or lvalue
        (outputs) of each nonzero: a format string with one ``{}`` for the
        nonzero index, e.g. ``"x[{}]"``, or one string per nonzero, e.g.
        ``["params->mass", ...]``.
    precision
        Literal suffix and maths-function names.
    real
        Name of the C floating type of the work variables.
    boolean_inputs
        Indices of the inputs whose every value the caller guarantees to be
        exactly 0 or 1 (validity flags): tests on them are written as
        compares with 0.5 and ``min``/``max``, which gcc compiles without branches.
    branch_free
        False writes every select in its plain C99 form (``c != 0 ? x : 0``,
        nested selects for logic), which gcc compiles to branches: the
        alternative ``wheelload bench speed`` measures the forms against.
    """
    if not f.is_a("SXFunction"):
        raise EmitError(f"{f.name()}: only SX Functions can be emitted, got {f.class_name()}")
    if len(inputs) != f.n_in() or len(outputs) != f.n_out():
        raise EmitError(
            f"{f.name()}: has {f.n_in()} inputs and {f.n_out()} outputs, "
            f"got {len(inputs)} and {len(outputs)} C names"
        )
    suffix = "f" if precision is Precision.FLOAT else ""
    one, zero = literal(1.0, precision), literal(0.0, precision)
    values = _Values()
    lines = []
    used = set()
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op == ca.OP_OUTPUT:
            (work,) = f.instruction_input(k)
            index, nz = f.instruction_output(k)
            lines.append(f"{_element(outputs[index], nz)} = w{work};")
            continue
        (target,) = f.instruction_output(k)
        used.add(target)
        if op == ca.OP_INPUT:
            index, nz = f.instruction_input(k)
            expression = _element(inputs[index], nz)
            boolean = index in boolean_inputs
            values.define(target, truth=boolean, number=boolean, constant=None)
        elif op == ca.OP_CONST:
            value = f.instruction_constant(k)
            expression = literal(value, precision)
            values.define(target, truth=value in (0.0, 1.0), number=True, constant=value)
        elif op in _TEMPLATES:
            operands = [w for w in f.instruction_input(k) if w >= 0]
            expression = (branch_free and _select(op, operands, values, precision)) or _TEMPLATES[
                op
            ].format(*(f"w{w}" for w in operands), f=suffix, one=one, zero=zero)
            truth, number = values.after(op, operands)
            values.define(target, truth=truth, number=number, constant=None)
        else:
            raise EmitError(
                f"{f.name()}: operation '{OPERATION_NAMES.get(op, op)}' at instruction {k} "
                "has no C form in wheelload's emitter"
            )
        lines.append(f"w{target} = {expression};")
    declarations = [f"{real} {', '.join(f'w{w}' for w in sorted(used))};"] if used else []
    return "\n".join(declarations + lines)
