"""The registry of wheel-load estimators: every method named once, with its paper reference.

Each method lives in its own module, which exports ``INFO``: a
:class:`~wheelload.estimators.protocol.MethodInfo`, or a tuple of them for a
module with variants (the KF and its projection variants). The modules are
listed in table order, the core estimators (:data:`CORE_MODULES`) then the
papers' comparison methods (:data:`FAMILY_MODULES`, in
``wheelload.estimators.family``); one that is not (yet) installed is left
out, any other import error is raised. Studies and the command line reach
estimators only through :func:`build`.

Vehicle model: the family methods take the suspension pseudo-measurement and
the rigid-body equilibrium from the same model Functions as the two-stage KF
(every model term the vehicle file switches on), so that a comparison ranks
estimators, not models; ``build(name, vehicle, suspension=SuspensionModel.PAPER)``
gives a family method with the source paper's bare model instead
(:mod:`wheelload.estimators.family.suspension_model`). The core estimators
always use the vehicle file's model (switch its ``[model]`` terms off for
theirs).

Example
-------
>>> sorted(methods())
['B', 'C', ...]
>>> estimate = build("C", vehicle).run(signals)
"""

from __future__ import annotations

import functools
import importlib

from wheelload.estimators.method_options import UnknownOptionError as UnknownOptionError
from wheelload.estimators.method_options import check_options
from wheelload.estimators.protocol import DEFAULT_MODEL, Estimator, MethodInfo, SuspensionModel
from wheelload.models import Vehicle

#: Modules of the core estimators, in table order; each exports ``INFO`` (one or a tuple).
CORE_MODULES = (
    "wheelload.estimators.kf.method",  # kf, projection-mp, projection-ls
    "wheelload.estimators.mhe.method",  # mhe
)
#: Modules of ``wheelload.estimators.family``, in table order; each exports ``INFO``.
FAMILY_MODULES = (
    "algebraic",  # B
    "quasi_static",  # C
    "suspension_only",  # D
    "quarter_car",  # E
    "quarter_car_constrained",  # E+C
    "strong_tracking_ukf",  # F
    "ycoo",
    "umvf",
    "road_angle",
    "corner",
)
FAMILY_PACKAGE = "wheelload.estimators.family"
#: Modules of the tyre-force methods (F_x, F_y per wheel beside the KF's F_z), in
#: ``wheelload.estimators.family``: a table of their own, so that the load studies
#: (:func:`methods`) do not rank them as load estimators.
TYRE_MODULES = ("tyres.forces",)


class UnknownMethodError(ValueError):
    """A method name that is not registered (the message lists the known ones)."""


def _module_infos(modules: tuple[str, ...]) -> list[MethodInfo]:
    """The ``INFO`` entries of the installed ``modules``, in order."""
    infos = []
    for full in modules:
        try:
            loaded = importlib.import_module(full)
        except ModuleNotFoundError as error:
            if error.name == full:
                continue  # not installed in this build
            raise
        entries = loaded.INFO if isinstance(loaded.INFO, tuple) else (loaded.INFO,)
        for info in entries:
            if not isinstance(info, MethodInfo):
                raise TypeError(f"{full}.INFO must be a MethodInfo, got {type(info).__name__}")
        infos.extend(entries)
    return infos


@functools.cache
def core() -> tuple[MethodInfo, ...]:
    """The core estimators (KF, projection KFs, MHE), in table order."""
    return tuple(_module_infos(CORE_MODULES))


@functools.cache
def methods() -> dict[str, MethodInfo]:
    """Every registered method by name, in table order (core first)."""
    family = tuple(f"{FAMILY_PACKAGE}.{module}" for module in FAMILY_MODULES)
    table: dict[str, MethodInfo] = {}
    for info in (*core(), *_module_infos(family)):
        if info.name in table:
            raise ValueError(f"method name {info.name!r} is registered twice")
        table[info.name] = info
    return table


@functools.cache
def tyre_methods() -> dict[str, MethodInfo]:
    """The tyre-force methods by name (``tyre-pid``, ``tyre-lateral``, ``tyre-forces``,
    ``tyre-rigid``); :func:`build` builds them as any other."""
    infos = _module_infos(tuple(f"{FAMILY_PACKAGE}.{module}" for module in TYRE_MODULES))
    return {info.name: info for info in infos}


def method(name: str) -> MethodInfo:
    """The registered method ``name`` (exact, else case-insensitive match), load or tyre.

    A core method's exact name is found importing its own module only (not the MHE's
    OSQP set-up for the KF, nor the family's modules).
    """
    for module in CORE_MODULES:
        for info in _module_infos((module,)):
            if info.name == name:
                return info
    table = {**methods(), **tyre_methods()}
    if name in table:
        return table[name]
    folded = {key.lower(): info for key, info in table.items()}
    if name.lower() in folded:
        return folded[name.lower()]
    raise UnknownMethodError(f"unknown method {name!r}; known methods: {', '.join(table)}")


def build(
    name: str, vehicle: Vehicle, suspension: SuspensionModel = DEFAULT_MODEL, **options
) -> Estimator:
    """The estimator ``name`` for ``vehicle``; an unknown name raises UnknownMethodError.

    ``suspension`` chooses the vehicle model of a family method (module
    docstring); the core estimators ignore it (:attr:`MethodInfo.model_choice`).
    ``options`` are the fields of the method's options dataclass
    (:attr:`MethodInfo.options`: the KF's ``static``, ``step``, ``guard_settings``,
    ...), checked first: one it does not declare, or of another type, raises
    :class:`UnknownOptionError` naming the option, the method and the valid options.
    """
    info = method(name)
    check_options(info, options)
    if info.model_choice:
        return info.build(vehicle, suspension=suspension, **options)
    return info.build(vehicle, **options)
