"""The API reference pages: the contract first, then the internals, package by package.

The contract (``reference/contract.rst``) is what a user imports: ``wheelload``'s top level
and the faces of :mod:`wheelload.estimators` and :mod:`wheelload.models`, each name under
the heading of :data:`CONTRACT` that says what it is for. A face that gains or loses a
name without this table following stops the build (:class:`ContractError`), so the
contract page is always the face's own list. The internals (one page per package, written
from the packages, in the code's own layout) document every other public member, leaving
out the contract's names so that each object is described once.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from pathlib import Path

ROOTS = ("wheelload.models", "wheelload.estimators", "wheelload.studies")
SKIPPED = {"wheelload.studies.docs.conf"}

#: The faces of the contract, each name under a heading (every name of the face's __all__,
#: once).
CONTRACT: dict[str, tuple[tuple[str, tuple[str, ...]], ...]] = {
    "wheelload.estimators": (
        (
            "Methods: build one, list them",
            (
                "build",
                "method",
                "methods",
                "tyre_methods",
                "MethodInfo",
                "Estimator",
                "SuspensionModel",
                "DEFAULT_MODEL",
                "UnknownMethodError",
                "UnknownOptionError",
            ),
        ),
        ("Results", ("Estimate", "StepFlag")),
        (
            "Logs",
            (
                "read_log",
                "write_log",
                "signals_from_frame",
                "Signals",
                "Sample",
                "LogError",
                "scan_log",
                "LogStream",
            ),
        ),
        (
            "Each method's options (build's keywords)",
            (
                "KfOptions",
                "ProjectionOptions",
                "MheOptions",
                "AlgebraicOptions",
                "QuarterCarOptions",
                "StrongTrackingOptions",
                "YcooOptions",
                "UmvfOptions",
                "RoadAngleOptions",
                "CornerOptions",
                "TyreForcesOptions",
                "TyreOptions",
            ),
        ),
        (
            "The settings the options take",
            (
                "MheSettings",
                "Arrival",
                "BiasStates",
                "Constraint",
                "Loss",
                "ResidualLoss",
                "GuardSettings",
                "guard_settings_for",
                "GUARDS_OFF",
                "FAULT_CHANNELS",
                "TyreSettings",
                "Precision",
            ),
        ),
        ("Weighing at standstill", ("weigh", "WeighSettings", "sprung_geometry")),
        ("Order statistics", ("percentile", "linear_percentile")),
    ),
    "wheelload.models": (
        (
            "The vehicle file",
            (
                "load_vehicle",
                "vehicle_template",
                "example_vehicle_path",
                "vehicle_from_dict",
                "Vehicle",
                "ModelTerms",
                "VehicleFileError",
            ),
        ),
        ("Mass properties", ("static_loads", "vehicle_mass_centre", "MassCentre")),
        (
            "The symbolic models (CasADi Functions)",
            (
                "suspension_function",
                "travel_function",
                "equilibrium_function",
                "paper_equilibrium_function",
                "gates_function",
                "ModelParameters",
            ),
        ),
        (
            "Conventions and inputs",
            ("WHEELS", "GRAVITY", "INPUTS", "OPTIONAL_INPUTS", "DROPPABLE", "GATES"),
        ),
    ),
}


class ContractError(ValueError):
    """A face's names and :data:`CONTRACT` disagree (the message names them)."""


def contract_names(face: str) -> list[str]:
    """The names :data:`CONTRACT` lists for ``face``, checked against its ``__all__``."""
    listed = [name for _, names in CONTRACT[face] for name in names]
    exported = set(importlib.import_module(face).__all__)
    twice = sorted({name for name in listed if listed.count(name) > 1})
    missing, extra = sorted(exported - set(listed)), sorted(set(listed) - exported)
    if twice or missing or extra:
        raise ContractError(
            f"{face}: the reference's CONTRACT (studies/docs/reference.py) lists "
            f"{twice or 'none'} twice, lacks {missing or 'none'} and has {extra or 'none'} "
            "the face does not export: make it the face's __all__"
        )
    return listed


def _directive(face: str, name: str) -> list[str]:
    """The autodoc lines of one contract name (a class with its members)."""
    value = getattr(importlib.import_module(face), name)
    if inspect.isclass(value):
        return [f".. autoclass:: {face}.{name}", "   :members:", ""]
    if callable(value):
        return [f".. autofunction:: {face}.{name}", ""]
    return [f".. autodata:: {face}.{name}", "   :no-value:", ""]


def contract_page() -> str:
    """The reStructuredText of the contract: the top level, then each face by heading."""
    title = "The contract"
    lines = [title, "=" * len(title), ""]
    lines += [
        "What a program imports: ``wheelload``'s top level and the faces of",
        ":mod:`wheelload.estimators` and :mod:`wheelload.models`. Everything else is in the",
        "internals, which may change between versions.",
        "",
        "wheelload",
        "---------",
        "",
        ".. automodule:: wheelload",
        "   :no-members:",
        "",
    ]
    for face, groups in CONTRACT.items():
        contract_names(face)
        lines += [face, "-" * len(face), "", f".. automodule:: {face}", "   :no-members:"]
        lines += ["   :no-index:", ""]  # the face's own entry is its internals page
        for heading, names in groups:
            lines += [heading, "^" * len(heading), ""]
            for name in names:
                lines += _directive(face, name)
    return "\n".join(lines)


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


def _contract_objects() -> set[tuple[str, int]]:
    """(name, id) of each contract object: a module's member of that name that is that
    object is described in the contract, not again in the internals."""
    found = set()
    for face in CONTRACT:
        module = importlib.import_module(face)
        found |= {(name, id(getattr(module, name))) for name in contract_names(face)}
    return found


def package_page(package: str, contract: set[tuple[str, int]] | None = None) -> str:
    """The reStructuredText of one package's page (the contract's objects left out)."""
    contract = _contract_objects() if contract is None else contract
    lines = [package, "=" * len(package), "", f".. automodule:: {package}", "   :no-members:", ""]
    for name in modules(package):
        module = importlib.import_module(name)
        described = sorted(
            member for member, value in vars(module).items() if (member, id(value)) in contract
        )
        lines += [name, "-" * len(name), "", f".. automodule:: {name}", "   :members:"]
        if described:
            lines.append(f"   :exclude-members: {', '.join(described)}")
        lines.append("")
    return "\n".join(lines)


def write_reference(folder: Path) -> list[Path]:
    """Write ``index.rst``, the contract and one page per package into ``folder``; the
    pages written."""
    folder.mkdir(parents=True, exist_ok=True)
    contract = folder / "contract.rst"
    contract.write_text(contract_page())
    written = [contract]
    objects = _contract_objects()
    names = packages()
    for package in names:
        page = folder / f"{package}.rst"
        page.write_text(package_page(package, objects))
        written.append(page)
    toc = ["API reference", "=============", ""]
    toc += [
        "The contract is what a program imports and what this version promises; the",
        "internals document each package's modules, for reading the code.",
        "",
        ".. toctree::",
        "   :caption: The contract",
        "   :maxdepth: 1",
        "",
        "   contract",
        "",
        ".. toctree::",
        "   :caption: Internals",
        "   :maxdepth: 1",
        "",
    ]
    toc += [f"   {package}" for package in names]
    index = folder / "index.rst"
    index.write_text("\n".join(toc) + "\n")
    return [index, *written]
