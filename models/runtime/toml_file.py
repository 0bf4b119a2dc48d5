"""Read a TOML file (vehicle file, channel map): every error names the file and says what to do.

A :class:`TomlFileKind` holds the error class and the messages of one kind of
file; :func:`read_toml` raises that class with ``"<path>: <message>"``.

Example
-------
>>> table = read_toml(Path("car.toml"), VEHICLE_FILE)
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True, kw_only=True)
class TomlFileKind:
    """Messages of one kind of TOML file (``{byte}``, ``{error}`` filled in)."""

    error: type[ValueError]
    missing: str  # no such file
    folder: str  # the path is a folder
    not_utf8: str  # {byte}: the first byte that is not UTF-8
    not_toml: str  # {error}: the TOML parser's message
    unreadable: str  # {error}: the operating system's message


def read_toml(path: Path, kind: TomlFileKind) -> dict:
    """The parsed table of the TOML file at ``path``, or ``kind.error`` naming the file."""

    def fail(message: str) -> ValueError:
        return kind.error(f"{path}: {message}")

    if path.is_dir():
        raise fail(kind.folder)
    try:
        with path.open("rb") as stream:
            return tomllib.load(stream)
    except FileNotFoundError:
        raise fail(kind.missing) from None
    except UnicodeDecodeError as error:
        raise fail(kind.not_utf8.format(byte=error.start)) from None
    except tomllib.TOMLDecodeError as error:
        raise fail(kind.not_toml.format(error=error)) from None
    except OSError as error:
        raise fail(kind.unreadable.format(error=error)) from None
