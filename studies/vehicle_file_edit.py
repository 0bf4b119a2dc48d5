"""Write a copy of a vehicle file with some values changed, keeping its comments.

The copy is the original text with the value of each named ``[table] key``
line replaced (its trailing comment kept), checked by reading it back as a
vehicle, written to a temporary file in the target folder and renamed. No
input file is ever replaced, and an existing file only with ``force``.
"""

from __future__ import annotations

import re
from pathlib import Path

from wheelload.models.files.temporaries import replacing
from wheelload.models.vehicle import load_vehicle

_TABLE = re.compile(r"^\s*\[([^\[\]]+)\]\s*(#.*)?$")
_KEY = re.compile(r"^(\s*)([A-Za-z0-9_]+)(\s*=\s*)([^#\n]*?)(\s*)(#.*)?$")


def edited_vehicle_text(text: str, changes: dict[tuple[str, str], float]) -> str:
    """``text`` with each ``(table, key)`` set to its new value; every key must exist once."""
    table = ""
    found: set[tuple[str, str]] = set()
    lines = []
    for line in text.splitlines(keepends=True):
        body = line.rstrip("\n")
        header = _TABLE.match(body)
        if header:
            table = header.group(1).strip()
        else:
            match = _KEY.match(body)
            if match and (table, match.group(2)) in changes:
                name = (table, match.group(2))
                if name in found:
                    raise ValueError(f"key '{table}.{name[1]}' appears twice in the vehicle file")
                found.add(name)
                indent, key, equals, _, space, comment = match.groups()
                value = f"{changes[name]:.6g}"
                body = f"{indent}{key}{equals}{value}{space or ''}{comment or ''}".rstrip()
        lines.append(body + ("\n" if line.endswith("\n") else ""))
    missing = [f"{t}.{k}" for t, k in changes if (t, k) not in found]
    if missing:
        raise ValueError(f"vehicle file has no key '{missing[0]}' to update")
    return "".join(lines)


def check_target(target: Path, inputs: tuple[Path, ...], *, force: bool) -> None:
    """Refuse an output path that is an input, or that exists without ``force``."""
    if Path(target).resolve() in {Path(p).resolve() for p in inputs}:
        raise ValueError(f"{target}: is an input file; choose another --out (inputs are kept)")
    if Path(target).exists() and not force:
        raise ValueError(f"{target}: exists; give --force to replace it")
    if not Path(target).resolve().parent.is_dir():
        raise ValueError(f"{target}: folder does not exist")


def write_vehicle_copy(
    source: Path,
    target: Path,
    changes: dict[tuple[str, str], float],
    *,
    inputs: tuple[Path, ...] = (),
    force: bool = False,
) -> None:
    """Write ``source`` with ``changes`` to ``target`` (temporary file, then rename)."""
    target = Path(target)
    check_target(target, (Path(source), *inputs), force=force)
    text = edited_vehicle_text(Path(source).read_text(encoding="utf-8"), changes)
    with replacing(target) as temporary:
        temporary.write_text(text, encoding="utf-8")
        load_vehicle(temporary)  # the copy must be a valid vehicle file
