"""Write a changed copy of a vehicle file: new values with a comment, the rest kept verbatim.

The input is never overwritten; an existing output is refused unless
``force``; the text goes to a temporary file in the target folder, is read
back by the vehicle-file reader, and is then renamed into place.

Example
-------
>>> text = set_values(source_text, {("suspension", "front", "spring_rate"): (61200.0, "± 150")})
>>> write_vehicle_text(text, "new.toml", inputs=("old.toml",), force=False)
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from wheelload.models import load_vehicle
from wheelload.models.files.temporaries import replacing

Key = tuple[str, ...]
TABLE = re.compile(r"^\s*\[([^\[\]]+)\]\s*(#.*)?$")
ASSIGNMENT = re.compile(r"^(\s*)([A-Za-z0-9_]+)(\s*=\s*)([^#]*?)(\s*)(#.*)?$")


def _format(value) -> str:
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    return repr(float(f"{float(value):.6g}"))


def set_values(text: str, changes: dict[Key, tuple[object, str]]) -> str:
    """``text`` with each key's value replaced and its comment set (old comment kept above)."""
    lines = text.splitlines()
    table: tuple[str, ...] = ()
    done = set()
    out = []
    for line in lines:
        header = TABLE.match(line)
        if header:
            table = tuple(part.strip() for part in header.group(1).split("."))
            out.append(line)
            continue
        match = ASSIGNMENT.match(line)
        key = (*table, match.group(2)) if match else None
        if key in changes:
            value, comment = changes[key]
            indent, name, equals, _, _, old = match.groups()
            if old:
                out.append(f"{indent}# (input file) {old.lstrip('# ').rstrip()}")
            out.append(f"{indent}{name}{equals}{_format(value)}  # {comment}")
            done.add(key)
        else:
            out.append(line)
    missing = [key for key in changes if key not in done]
    if missing:
        raise ValueError(f"key '{'.'.join(missing[0])}' not found in the vehicle file")
    return "\n".join(out) + "\n"


def add_values(text: str, changes: dict[Key, tuple[object, str]]) -> str:
    """``text`` with each key set as :func:`set_values` does, or added at the end of its
    table when the file does not have it (an optional key); the table must exist."""
    present, missing = {}, {}
    keys = _assigned_keys(text)
    for key, change in changes.items():
        (present if key in keys else missing)[key] = change
    lines = set_values(text, present).splitlines()
    for key, (value, comment) in missing.items():
        table, name = key[:-1], key[-1]
        start = next(
            (
                i
                for i, line in enumerate(lines)
                if (match := TABLE.match(line))
                and tuple(part.strip() for part in match.group(1).split(".")) == table
            ),
            None,
        )
        if start is None:
            raise ValueError(f"table [{'.'.join(table)}] not found in the vehicle file")
        end = next((i for i in range(start + 1, len(lines)) if TABLE.match(lines[i])), len(lines))
        # After the table's last assignment (comments further down belong to the next table).
        last = max((i for i in range(start, end) if ASSIGNMENT.match(lines[i])), default=start)
        lines.insert(last + 1, f"{name} = {_format(value)}  # {comment}")
    return "\n".join(lines) + "\n"


def _assigned_keys(text: str) -> set[Key]:
    """Every ``table.key`` assigned in the text."""
    table: Key = ()
    keys = set()
    for line in text.splitlines():
        header = TABLE.match(line)
        if header:
            table = tuple(part.strip() for part in header.group(1).split("."))
            continue
        match = ASSIGNMENT.match(line)
        if match:
            keys.add((*table, match.group(2)))
    return keys


def prepend_comment(text: str, comment: str) -> str:
    """``text`` with comment lines added at the top."""
    return "".join(f"# {line}\n".replace("#  \n", "#\n") for line in comment.splitlines()) + text


def check_output_path(path: str | Path, inputs: tuple[str | Path, ...], force: bool) -> Path:
    """The output path, or an error: never an input, never an existing file without ``force``."""
    path = Path(path)
    for source in inputs:
        if Path(source).exists() and path.exists() and os.path.samefile(source, path):
            raise ValueError(f"--out {path} is an input file: choose another name")
        if Path(source).resolve() == path.resolve():
            raise ValueError(f"--out {path} is an input file: choose another name")
    if path.exists() and not force:
        raise ValueError(f"{path} exists: choose another --out or add --force")
    if path.suffix.lower() != ".toml":
        raise ValueError(f"--out {path}: a vehicle file must end in .toml")
    return path


def write_text_atomically(text: str, path: Path) -> None:
    """Write ``text`` to a temporary file beside ``path`` and rename it into place."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


def write_vehicle_text(
    text: str, path: str | Path, *, inputs: tuple[str | Path, ...], force: bool
) -> Path:
    """Validate ``text`` as a vehicle file and write it to ``path`` (see module docstring)."""
    path = check_output_path(path, inputs, force)
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
        load_vehicle(temporary)  # the copy must be a valid vehicle file
    return path
