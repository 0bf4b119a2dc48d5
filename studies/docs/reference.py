"""The API reference pages: one reStructuredText page per package, written from the packages.

Each page shows the package's face (its docstring; what it hands out is documented where it
is defined) and then each of its modules with their members, so the reference follows the
code's own layout and needs no hand-kept list.
"""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

ROOTS = ("wheelload.models", "wheelload.estimators", "wheelload.studies")
SKIPPED = {"wheelload.studies.docs.conf"}


def packages() -> list[str]:
    """Every package under :data:`ROOTS`, in order, the roots included."""
    found = []
    for root in ROOTS:
        found.append(root)
        module = importlib.import_module(root)
        for info in pkgutil.walk_packages(module.__path__, prefix=root + "."):
            if info.ispkg:
                found.append(info.name)
    return found


def modules(package: str) -> list[str]:
    """The plain modules (not sub-packages) directly inside ``package``."""
    module = importlib.import_module(package)
    names = [
        f"{package}.{info.name}"
        for info in pkgutil.iter_modules(module.__path__)
        if not info.ispkg and not info.name.startswith("_")
    ]
    return [name for name in sorted(names) if name not in SKIPPED]


def package_page(package: str) -> str:
    """The reStructuredText of one package's page."""
    lines = [package, "=" * len(package), "", f".. automodule:: {package}", "   :no-members:", ""]
    for name in modules(package):
        lines += [name, "-" * len(name), "", f".. automodule:: {name}", "   :members:", ""]
    return "\n".join(lines)


def write_reference(folder: Path) -> list[Path]:
    """Write ``index.rst`` and one page per package into ``folder``; the pages written."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    names = packages()
    for package in names:
        page = folder / f"{package}.rst"
        page.write_text(package_page(package))
        written.append(page)
    toc = ["API reference", "=============", "", ".. toctree::", "   :maxdepth: 1", ""]
    toc += [f"   {package}" for package in names]
    index = folder / "index.rst"
    index.write_text("\n".join(toc) + "\n")
    return [index, *written]
