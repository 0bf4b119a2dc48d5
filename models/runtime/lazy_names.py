"""Names of a package imported on first use (PEP 562 module ``__getattr__``).

A package face that re-exports slow-to-import modules (the MHE's OSQP, the
identification's scipy) names them here, so that a command that does not use
them does not pay for them.

``internal`` names are found the same way but are not the face's: neither ``dir()`` nor
the sorted names (``__all__``) show them (what the package's own studies take through
the door, not what a user imports).

Example
-------
>>> __getattr__, __dir__, LAZY_NAMES = lazy_names(__name__, {"pkg.slow": ("Fit",)})
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable


def lazy_names(
    package: str,
    modules: dict[str, tuple[str, ...]],
    internal: dict[str, tuple[str, ...]] | None = None,
) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """The package's ``__getattr__`` importing each name of ``modules`` and ``internal`` (by
    module) when first asked for, its ``__dir__`` (the names of ``modules`` and the module's
    own public and special names, so ``dir(package)`` shows the face before any is
    imported), and the sorted names of ``modules`` (for ``__all__``)."""
    face = {name: module for module, names in modules.items() for name in names}
    table = {name: module for module, names in (internal or {}).items() for name in names}
    table.update(face)

    def __getattr__(name: str):
        if name not in table:
            raise AttributeError(f"module '{package}' has no attribute '{name}'")
        value = getattr(importlib.import_module(table[name]), name)
        setattr(sys.modules[package], name, value)  # found directly from now on
        return value

    def __dir__() -> list[str]:
        own = vars(sys.modules[package])
        shown = {name for name in own if name.startswith("__") or not name.startswith("_")}
        shown.discard("lazy_names")  # the helper this face is built with, not part of it
        shown -= set(table) - set(face)  # an internal name once imported
        return sorted(shown | set(face))

    return __getattr__, __dir__, sorted(face)
