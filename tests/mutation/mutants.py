"""Mutants of a Python module: one plausible mistake each, found on the module's own AST.

The operators are mutmut's (the arithmetic, comparison and boolean operators swapped; a
number :math:`n \\to n + 1`; a sign dropped) and three of numeric code: ``fmin`` and
``fmax`` swapped (an envelope made one-sided), the two branches of an ``if_else`` swapped,
and the first two arguments of a call swapped (two weightings or two wheels exchanged).

A mutant replaces one expression's source text by its mutated form in parentheses, so the
rest of the file is untouched and the mutant reads as a one-line diff. Docstrings, error
messages, logging, annotations and decorators are not mutated: a mistake there changes
no number a user sees.

>>> [m.after for m in mutants("x = a + b\\n", "m.py")][:1]
['(a - b)']
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

#: Binary operators and the one each is mistaken for.
BINARY = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
          ast.Pow: ast.Mult, ast.FloorDiv: ast.Div, ast.Mod: ast.FloorDiv}  # fmt: skip
#: Comparison operators: the boundary moved, or the comparison reversed.
COMPARE = {ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt,
           ast.Eq: ast.NotEq, ast.NotEq: ast.Eq, ast.Is: ast.IsNot, ast.IsNot: ast.Is,
           ast.In: ast.NotIn, ast.NotIn: ast.In}  # fmt: skip
#: Functions mistaken for their counterpart (by the name called, module prefix kept).
COUNTERPART = {"fmin": "fmax", "fmax": "fmin", "minimum": "maximum", "maximum": "minimum",
               "min": "max", "max": "min", "logic_and": "logic_or", "logic_or": "logic_and",
               "floor": "ceil", "ceil": "floor", "sin": "cos", "cos": "sin"}  # fmt: skip
#: Functions whose two arguments commute: swapping them is no mistake.
COMMUTATIVE = {"fmin", "fmax", "minimum", "maximum", "min", "max", "logic_and", "logic_or",
               "hypot", "add", "multiply", "isclose", "allclose"}  # fmt: skip
#: Calls whose arguments are messages, not numbers.
QUIET_CALLS = {"print", "debug", "info", "warning", "warn", "error", "exception", "note"}


@dataclass(frozen=True)
class Mutant:
    """One mutation: ``before`` (lines ``line``-``end_line``, UTF-8 byte columns
    ``col``-``end_col``, as the AST gives them) becomes ``after``; ``operator`` names the
    kind of mistake."""

    path: str
    line: int
    col: int
    end_line: int
    end_col: int
    operator: str
    before: str
    after: str

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line}"

    def apply(self, source: str) -> str:
        """``source`` with this mutation made."""
        lines = source.splitlines(keepends=True)
        offsets = [0]
        for text in lines:
            offsets.append(offsets[-1] + len(text.encode()))
        raw = source.encode()
        start = offsets[self.line - 1] + self.col
        end = offsets[self.end_line - 1] + self.end_col
        return (raw[:start] + self.after.encode() + raw[end:]).decode()


def _quiet(node: ast.AST) -> bool:
    """A node whose numbers nobody reads: a message, a log line, a raise, an assert."""
    if isinstance(node, (ast.Raise, ast.Assert, ast.JoinedStr)):
        return True
    if isinstance(node, ast.Call):
        name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(
            node.func, "id", "")  # fmt: skip
        return name in QUIET_CALLS
    return False


def _called_name(node: ast.Call) -> str | None:
    if isinstance(node.func, ast.Attribute):
        return node.func.attr
    return node.func.id if isinstance(node.func, ast.Name) else None


def _with_name(func: ast.expr, name: str) -> ast.expr:
    if isinstance(func, ast.Attribute):
        return ast.Attribute(value=func.value, attr=name, ctx=ast.Load())
    return ast.Name(id=name, ctx=ast.Load())


class _Finder(ast.NodeVisitor):
    """Collects ``(node, operator, replacement)`` over the expressions that compute."""

    def __init__(self):
        self.found: list[tuple[ast.AST, str, ast.AST]] = []

    def generic_visit(self, node):
        if _quiet(node):
            return
        super().generic_visit(node)

    def _skip_docstring(self, node):
        body = node.body
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            body = body[1:]
        for child in body:
            self.visit(child)

    def visit_Module(self, node):
        self._skip_docstring(node)

    def visit_ClassDef(self, node):
        self._skip_docstring(node)

    def visit_FunctionDef(self, node):
        for default in (*node.args.defaults, *node.args.kw_defaults):
            if default is not None:
                self.visit(default)
        self._skip_docstring(node)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_AnnAssign(self, node):
        if node.value is not None:
            self.visit(node.value)

    def visit_Assign(self, node):
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            return
        self.generic_visit(node)

    def visit_BinOp(self, node):
        if type(node.op) in BINARY:
            self.found.append((node, "binary", ast.BinOp(node.left, BINARY[type(node.op)](),
                                                         node.right)))  # fmt: skip
        self.generic_visit(node)

    def visit_UnaryOp(self, node):
        if isinstance(node.op, ast.USub):
            self.found.append((node, "sign", node.operand))
        elif isinstance(node.op, ast.Not):
            self.found.append((node, "not", node.operand))
        self.generic_visit(node)

    def visit_Compare(self, node):
        if len(node.ops) == 1 and type(node.ops[0]) in COMPARE:
            swapped = ast.Compare(node.left, [COMPARE[type(node.ops[0])]()], node.comparators)
            self.found.append((node, "compare", swapped))
        self.generic_visit(node)

    def visit_BoolOp(self, node):
        other = ast.Or() if isinstance(node.op, ast.And) else ast.And()
        self.found.append((node, "boolean", ast.BoolOp(other, node.values)))
        self.generic_visit(node)

    def visit_Constant(self, node):
        value = node.value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            self.found.append((node, "number", ast.Constant(value + 1)))

    def visit_Call(self, node):
        if _quiet(node):
            return
        name = _called_name(node)
        if name in COUNTERPART:
            self.found.append((node, "counterpart", ast.Call(
                _with_name(node.func, COUNTERPART[name]), node.args, node.keywords)))  # fmt: skip
        positional = [a for a in node.args if not isinstance(a, ast.Starred)]
        if name == "if_else" and len(positional) >= 3:
            args = [positional[0], positional[2], positional[1], *positional[3:]]
            self.found.append((node, "branches", ast.Call(node.func, args, node.keywords)))
        elif (
            len(positional) >= 2 and len(positional) == len(node.args) and (name not in COMMUTATIVE)
        ):
            first, second = (ast.unparse(a) for a in positional[:2])
            if first != second:
                args = [positional[1], positional[0], *positional[2:]]
                self.found.append((node, "arguments", ast.Call(node.func, args, node.keywords)))
        self.generic_visit(node)


def mutants(source: str, path: str) -> list[Mutant]:
    """Every mutant of ``source`` (the module at ``path``), in source order."""
    finder = _Finder()
    finder.visit(ast.parse(source))
    found = []
    for node, operator, replacement in finder.found:
        before = ast.get_source_segment(source, node)
        if before is None:
            continue
        found.append(Mutant(path, node.lineno, node.col_offset, node.end_lineno,
                            node.end_col_offset, operator, before,
                            f"({ast.unparse(replacement)})"))  # fmt: skip
    return sorted(found, key=lambda m: (m.line, m.col, m.operator, m.after))
