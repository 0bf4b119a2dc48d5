"""Named CasADi Functions kept on disk between runs (serialised CasADi).

Building a Function from the models' expressions (the filter step with its
Jacobians and guards, the suspension pseudo-measurement, the equilibrium rows)
takes from a few milliseconds to a fifth of a second; loading its serialised
form takes well under a millisecond for a model Function. A stored Function is
named by its builder (module and name) and :func:`code_digest` (a hash of every
``.py`` file of ``wheelload.models`` and ``wheelload.estimators`` and of the CasADi
version), so an edit of any of them builds it again. It lives in the private build folder
(:func:`~wheelload.models.runtime.build_folder.build_folder`), written to a
temporary file and renamed into place; a file that does not load is built
again (with a one-line note).

Example
-------
>>> z = stored_function(suspension_function)  # the Function suspension_function() builds
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import importlib.util
import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca

from wheelload.models.runtime.build_folder import build_folder
from wheelload.models.runtime.temporaries import replacing

_log = logging.getLogger(__name__)

#: ``id`` of each Function :func:`stored_function` returned: its file stem (name and digest)
#: and the Function itself (kept, so that its id names no other Function).
_STEMS: dict[int, tuple[str, ca.Function]] = {}

#: The folders of the package whose sources the stored Functions and libraries are built from.
SOURCE_FOLDERS = ("models", "estimators")
#: The package's folder (``models/runtime/`` is two below it).
PACKAGE_ROOT = Path(__file__).resolve().parents[2]


@functools.cache
def code_digest(root: Path = PACKAGE_ROOT) -> str:
    """Hash of the ``.py`` files of :data:`SOURCE_FOLDERS` under ``root`` and of the CasADi
    version."""
    digest = hashlib.sha256(f"casadi {casadi_version()}\n".encode())
    for folder in SOURCE_FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            digest.update(f"{path.relative_to(root)}\n".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def casadi_version() -> str:
    """The installed CasADi's version, from its distribution record beside the package (read
    without importing CasADi, which takes about 30 ms); from CasADi where there is none."""
    spec = importlib.util.find_spec("casadi")
    if spec is not None and spec.origin is not None:
        records = sorted(Path(spec.origin).parents[1].glob("casadi-*.dist-info"))
        if len(records) == 1:
            return records[0].name.removeprefix("casadi-").removesuffix(".dist-info")
    return ca.__version__


@functools.cache
def stored_function(builder: Callable[[], ca.Function]) -> ca.Function:
    """``builder()``, loaded from the build folder when this code built it before (module
    docstring); the same object for the same builder in one process."""
    stem = builder_stem(builder)
    function = _load_or_build(builder, build_folder() / f"{stem}.casadi")
    _STEMS[id(function)] = (stem, function)
    return function


@dataclass(frozen=True)
class Builder:
    """A Function builder named by its module and name, imported only when it is called: a
    warm run that finds what is stored of its Function never imports the module (nor the
    symbolic models it builds from)."""

    module: str
    name: str

    def __call__(self) -> ca.Function:
        return getattr(importlib.import_module(self.module), self.name)()


def builder_name(builder: Callable[[], ca.Function]) -> tuple[str, str]:
    """The module and the name of a builder function or :class:`Builder`."""
    if isinstance(builder, Builder):
        return builder.module, builder.name
    return builder.__module__, builder.__qualname__


def builder_stem(builder: Callable[[], ca.Function]) -> str:
    """``MODULE.BUILDER_DIGEST``: the name of what is stored of ``builder()``'s Function
    (the builder's module and name, :func:`code_digest`; a :class:`Builder` the same as
    the function it names)."""
    module, name = builder_name(builder)
    return f"{module.rsplit('.', 1)[-1]}.{name}_{code_digest()}"


def stored_stem(function: ca.Function) -> str | None:
    """``BUILDER_DIGEST`` of a Function :func:`stored_function` returned (what the code alone
    determines it by: a key for what is built from it), None for any other Function."""
    stem, stored = _STEMS.get(id(function), (None, None))
    return stem if stored is function else None


def _load_or_build(builder: Callable[[], ca.Function], path: Path) -> ca.Function:
    if path.exists():
        try:
            return ca.Function.deserialize(path.read_text())
        except (RuntimeError, OSError, UnicodeDecodeError):  # truncated or corrupt
            _log.warning("wheelload: note: cached function %s does not load: built again", path)
    function = builder()
    store_text(path, function.serialize())
    return function


def store_text(path: Path, text: str) -> None:
    """``text`` into ``path`` through a temporary renamed into place; nothing if that fails
    (what is not stored is made again next time)."""
    try:
        with replacing(path) as temporary:
            temporary.write_text(text)
    except OSError:
        pass
