"""The vehicle file: read it, and write a copy with values changed, keeping its comments.

Reading: :func:`load_vehicle` (TOML, then the sections of
:mod:`wheelload.models.vehicle.description`, then the ranges of
:mod:`wheelload.models.vehicle.plausibility`); every error names the file and the key.

Writing: the copy is the original text with the value of each named
``[table] key`` line replaced (:func:`replace_values`), everything else kept
verbatim. It is checked by reading it back as a vehicle, written to a
temporary file in the target folder and renamed
(:func:`wheelload.models.runtime.temporaries.replacing`). No input file is ever
replaced, and an existing file only with ``force``.

Example
-------
>>> vehicle = load_vehicle(example_vehicle_path())
>>> text = set_values(vehicle_template(), {("mass", "total"): (1620.0, "weighed")})
>>> write_vehicle_text(text, "new.toml", inputs=(example_vehicle_path(),), force=False)
"""

from __future__ import annotations

import os
import re
from importlib import resources
from pathlib import Path

from wheelload.models.runtime.temporaries import replacing
from wheelload.models.runtime.toml_file import TomlFileKind, read_toml
from wheelload.models.vehicle.description import Vehicle, VehicleFileError, vehicle_from_dict
from wheelload.models.vehicle.plausibility import check_vehicle_ranges

#: A key's place in the file: its table's dotted parts, then the key.
Key = tuple[str, ...]
TABLE = re.compile(r"^\s*\[([^\[\]]+)\]\s*(#.*)?$")
VEHICLE_FILE = TomlFileKind(
    error=VehicleFileError,
    missing="no such vehicle file",
    folder="is a folder: give a vehicle TOML file",
    not_utf8="is not UTF-8 text (byte {byte}): save the vehicle file as UTF-8",
    not_toml="not valid TOML: {error}",
    unreadable="the vehicle file cannot be read: {error}",
)
ASSIGNMENT = re.compile(r"^(\s*)([A-Za-z0-9_]+)(\s*=\s*)(\[[^\]]*\]|[^#\n]*?)(\s*)(#.*)?$")


def load_vehicle(path: str | Path, *, allow_unusual: bool = False) -> Vehicle:
    """Read a vehicle TOML file; errors name the file and the offending key.

    Values outside the physical ranges of :mod:`wheelload.models.vehicle.plausibility`
    are refused unless ``allow_unusual``.
    """
    path = Path(path)
    table = read_toml(path, VEHICLE_FILE)
    try:
        vehicle = vehicle_from_dict(table)
    except VehicleFileError as error:
        raise VehicleFileError(f"{path}: {error}") from None
    violations = [] if allow_unusual else check_vehicle_ranges(vehicle)
    if violations:
        raise VehicleFileError(
            f"{path}: "
            + "; ".join(str(v) for v in violations)
            + "; correct the file, or give --allow-unusual for a special vehicle"
        )
    return vehicle


def example_vehicle_path() -> Path:
    """Path of the bundled reference vehicle (paper Table I sports car)."""
    return Path(str(resources.files("wheelload.models") / "vehicles" / "sports_car.toml"))


def vehicle_template() -> str:
    """A fully commented vehicle file (the bundled reference vehicle) to edit."""
    return example_vehicle_path().read_text(encoding="utf-8")


def table_key(header: re.Match) -> Key:
    """The dotted parts of a ``[table]`` header."""
    return tuple(part.strip() for part in header.group(1).split("."))


def replace_values(
    text: str, values: dict[Key, str], comments: dict[Key, str] | None = None
) -> str:
    """``text`` with each key's value replaced by its TOML text; every key must exist once.

    A key's trailing comment is kept, or, for a key in ``comments``, replaced
    by that comment (the old one kept on a line above, ``# (input file) ...``).
    """
    comments = comments or {}
    table: Key = ()
    found: set[Key] = set()
    lines = []
    for line in text.splitlines(keepends=True):
        body = line.rstrip("\n")
        header = TABLE.match(body)
        match = None if header else ASSIGNMENT.match(body)
        if header:
            table = table_key(header)
        elif match and (*table, match.group(2)) in values:
            key = (*table, match.group(2))
            if key in found:
                raise ValueError(f"key '{'.'.join(key)}' appears twice in the vehicle file")
            found.add(key)
            indent, name, equals, _, space, comment = match.groups()
            if key in comments:
                if comment:
                    lines.append(f"{indent}# (input file) {comment.lstrip('# ').rstrip()}\n")
                body = f"{indent}{name}{equals}{values[key]}  # {comments[key]}"
            else:
                body = f"{indent}{name}{equals}{values[key]}{space}{comment or ''}".rstrip()
        lines.append(body + ("\n" if line.endswith("\n") else ""))
    missing = [key for key in values if key not in found]
    if missing:
        raise ValueError(f"the vehicle file has no key '{'.'.join(missing[0])}'")
    return "".join(lines)


def edited_vehicle_text(text: str, changes: dict[tuple[str, str], float]) -> str:
    """``text`` with each ``(table, key)`` set to its value (6 digits), comments kept."""
    values = {(*table.split("."), key): f"{value:.6g}" for (table, key), value in changes.items()}
    return replace_values(text, values)


def number_text(value) -> str:
    """A number (or a list of numbers) to 6 significant digits, as TOML text."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(number_text(v) for v in value) + "]"
    return repr(float(f"{float(value):.6g}"))


def set_values(text: str, changes: dict[Key, tuple[object, str]]) -> str:
    """``text`` with each key's value replaced and its comment set (old comment kept above)."""
    values = {key: number_text(value) for key, (value, _) in changes.items()}
    comments = {key: comment for key, (_, comment) in changes.items()}
    return replace_values(text, values, comments)


def assigned_keys(text: str) -> set[Key]:
    """Every ``table.key`` assigned in the text."""
    table: Key = ()
    keys = set()
    for line in text.splitlines():
        header = TABLE.match(line)
        if header:
            table = table_key(header)
        elif match := ASSIGNMENT.match(line):
            keys.add((*table, match.group(2)))
    return keys


def add_values(text: str, changes: dict[Key, tuple[object, str]]) -> str:
    """``text`` with each key set as :func:`set_values` does, or added at the end of its
    table when the file does not have it (an optional key); the table must exist."""
    keys = assigned_keys(text)
    present = {key: change for key, change in changes.items() if key in keys}
    lines = set_values(text, present).splitlines()
    for key, (value, comment) in changes.items():
        if key in present:
            continue
        table, name = key[:-1], key[-1]
        start = next(
            (
                i
                for i, line in enumerate(lines)
                if (match := TABLE.match(line)) and table_key(match) == table
            ),
            None,
        )
        if start is None:
            raise ValueError(f"table [{'.'.join(table)}] not found in the vehicle file")
        end = next((i for i in range(start + 1, len(lines)) if TABLE.match(lines[i])), len(lines))
        # After the table's last assignment (comments further down belong to the next table).
        last = max((i for i in range(start, end) if ASSIGNMENT.match(lines[i])), default=start)
        lines.insert(last + 1, f"{name} = {number_text(value)}  # {comment}")
    return "\n".join(lines) + "\n"


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
    text: str,
    path: str | Path,
    *,
    inputs: tuple[str | Path, ...],
    force: bool,
    allow_unusual: bool = False,
) -> Path:
    """Validate ``text`` as a vehicle file (``allow_unusual``: as :func:`load_vehicle`'s) and
    write it to ``path`` (see module docstring)."""
    path = check_output_path(path, inputs, force)
    path.parent.mkdir(parents=True, exist_ok=True)
    with replacing(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
        load_vehicle(temporary, allow_unusual=allow_unusual)  # the copy must be valid
    return path
