"""OSQP's generated workspace made re-entrant: the solver of one MHE instance in a struct.

OSQP's embedded code generator writes the solver's workspace as file-scope objects
(``wheelload_mhe_solver`` and the settings, data, factorisation and iterates it points to),
so a program has one solver. :func:`make_reentrant` rewrites that file,
``osqp/wheelload_mhe_workspace.c``, into

- ``wheelload_mhe_workspace.h``: ``wheelload_mhe_workspace``, a struct with one member per
  object of the generated file (same name without the prefix, same type and size), and
  ``wheelload_mhe_workspace_init(w)``, which gives a struct the generated initial values and
  points its objects at one another: ``&w->solver`` is then an ``OSQPSolver`` of its own;
- ``wheelload_mhe_workspace.c``: the initial values as constant tables, and that function.

OSQP's sources keep no state of their own (they act on the solver they are handed), so
several structs are several independent solvers. OSQP's example program and its build files
(``emosqp.c``, ``Makefile``, ``CMakeLists.txt``, ``setup.py``, ``bindings.cpp``) use the
file-scope solver and are removed.

The generated file holds four kinds of object, each read here: an array with initial values
(``OSQPInt name[n] = {...};``), a zeroed array (``OSQPFloat name[n];``), a struct whose
initialiser may point at other objects (``OSQPVectorf name = {name_val, 40};``), and an
absent array (``#define name (OSQP_NULL)``); anything else is an error naming the line.

Example
-------
>>> make_reentrant(Path("out/osqp"))
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

#: Prefix of every object of the generated workspace (``solver.codegen(prefix=...)``).
PREFIX = "wheelload_mhe_"
WORKSPACE = f"{PREFIX}workspace"
#: OSQP's files that use the file-scope solver: removed.
FILE_SCOPE_USERS = ("emosqp.c", "Makefile", "CMakeLists.txt", "setup.py", "bindings.cpp")

_DECLARATION = re.compile(
    rf"(?P<type>[A-Za-z_]\w*)\s+{PREFIX}(?P<name>\w+)\s*(?:\[(?P<size>\d+)\])?"
    r"\s*(?:=\s*\{(?P<values>.*)\})?",
    re.DOTALL,
)
_ABSENT = re.compile(rf"#define\s+{PREFIX}(\w+)\s+\(OSQP_NULL\)")


class WorkspaceFormatError(ValueError):
    """The generated workspace holds a declaration this module does not read."""


@dataclass(frozen=True)
class WorkspaceObject:
    """One object of the generated workspace."""

    type: str
    name: str  # without the prefix
    size: int | None  # elements of an array, None for a struct
    values: str | None  # the initialiser's text between the braces, None when zeroed


@dataclass(frozen=True)
class Workspace:
    """The generated workspace: its objects in file order, the absent arrays, its includes."""

    objects: tuple[WorkspaceObject, ...]
    absent: tuple[str, ...]
    includes: tuple[str, ...]


def parse_workspace(text: str) -> Workspace:
    """The objects of OSQP's generated ``wheelload_mhe_workspace.c``."""
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)
    includes, absent, body = [], [], []
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("#include"):
            includes.append(stripped)
        elif match := _ABSENT.fullmatch(stripped):
            absent.append(match.group(1))
        elif stripped.startswith("#"):
            raise WorkspaceFormatError(f"OSQP workspace: unexpected directive {stripped!r}")
        else:
            body.append(line)
    objects = []
    for statement in _statements("\n".join(body)):
        match = _DECLARATION.fullmatch(statement)
        if match is None:
            raise WorkspaceFormatError(f"OSQP workspace: unexpected declaration {statement!r}")
        size = match.group("size")
        objects.append(
            WorkspaceObject(
                type=match.group("type"),
                name=match.group("name"),
                size=None if size is None else int(size),
                values=match.group("values"),
            )
        )
    return Workspace(tuple(objects), tuple(absent), tuple(includes))


def _statements(text: str) -> list[str]:
    """The top-level statements of ``text`` (split at ``;`` outside braces and strings)."""
    statements, depth, quoted, start = [], 0, False, 0
    for k, char in enumerate(text):
        if char == '"':
            quoted = not quoted
        elif not quoted and char in "{}":
            depth += 1 if char == "{" else -1
        elif not quoted and depth == 0 and char == ";":
            statements.append(text[start:k].strip())
            start = k + 1
    if text[start:].strip():
        raise WorkspaceFormatError(f"OSQP workspace: unterminated {text[start:].strip()!r}")
    return [s for s in statements if s]


def _members(text: str, workspace: Workspace) -> str:
    """``text`` with each object of the workspace named as a member of ``w``."""
    known = {o.name for o in workspace.objects}
    absent = set(workspace.absent)

    def member(match: re.Match) -> str:
        name = match.group(1)
        if name in absent:
            return "OSQP_NULL"
        if name not in known:
            raise WorkspaceFormatError(f"OSQP workspace: {PREFIX}{name} is not declared")
        return f"w->{name}"

    return re.sub(rf"\b{PREFIX}(\w+)", member, text)


def reentrant_sources(workspace: Workspace) -> tuple[str, str]:
    """(header, source) of the re-entrant workspace (module docstring)."""
    members, tables, assignments = [], [], []
    for o in workspace.objects:
        if o.size is not None:
            members.append(f"    {o.type} {o.name}[{o.size}];")
            if o.values is None:
                assignments.append(f"    (void)memset(w->{o.name}, 0, sizeof w->{o.name});")
                continue
            if PREFIX in o.values:
                raise WorkspaceFormatError(f"OSQP workspace: array {o.name} points at objects")
            values = " ".join(o.values.split())
            tables.append(f"static const {o.type} initial_{o.name}[{o.size}] = {{{values}}};")
            assignments.append(
                f"    (void)memcpy(w->{o.name}, initial_{o.name}, sizeof w->{o.name});"
            )
        else:
            if o.values is None:
                raise WorkspaceFormatError(f"OSQP workspace: struct {o.name} has no initialiser")
            members.append(f"    {o.type} {o.name};")
            values = " ".join(_members(o.values, workspace).split())
            assignments.append(f"    w->{o.name} = ({o.type}){{{values}}};")
    includes = "\n".join(workspace.includes)
    header = HEADER.format(includes=includes, members="\n".join(members), name=WORKSPACE)
    source = SOURCE.format(
        name=WORKSPACE, tables="\n".join(tables), assignments="\n".join(assignments)
    )
    return header, source


def make_reentrant(osqp_folder: Path) -> None:
    """Rewrite ``osqp_folder``'s generated workspace in place (module docstring)."""
    osqp_folder = Path(osqp_folder)
    source = osqp_folder / f"{WORKSPACE}.c"
    header, body = reentrant_sources(parse_workspace(source.read_text()))
    (osqp_folder / f"{WORKSPACE}.h").write_text(header)
    source.write_text(body)
    for name in FILE_SCOPE_USERS:
        (osqp_folder / name).unlink(missing_ok=True)


HEADER = """/* {name}.h: OSQP's embedded solver for one MHE instance (generated by wheelload from
 * OSQP's workspace file, wheelload.estimators.codegen.mhe_workspace). */
#ifndef WHEELLOAD_MHE_WORKSPACE_H
#define WHEELLOAD_MHE_WORKSPACE_H

{includes}

/* One solver: the objects of OSQP's generated workspace as members (solver, settings, data,
 * factorisation, iterates). Holds pointers into itself: set up by {name}_init, not by
 * copying another. */
typedef struct {{
{members}
}} {name};

/* The generated initial values, and every object pointed at its own: &w->solver is then an
 * independent OSQPSolver. */
void {name}_init({name} *w);

#endif
"""

SOURCE = """/* {name}.c: generated by wheelload from OSQP's workspace file; see {name}.h. */
#include <string.h>

#include "{name}.h"

{tables}

void {name}_init({name} *w)
{{
{assignments}
}}
"""
