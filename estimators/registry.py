"""The registry of wheel-load estimators: every method named once, with its paper reference.

The four core estimators are registered here; each comparison method lives
in its own module ``wheelload.estimators.family.<module>`` that exports
``INFO: MethodInfo``. The modules are listed in :data:`FAMILY_MODULES`; one
that is not (yet) installed is left out, any other import error is raised.
Studies and the command line reach estimators only through :func:`build`.

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
from collections.abc import Callable
from dataclasses import dataclass

from wheelload.estimators.family.suspension_model import DEFAULT_MODEL, SuspensionModel
from wheelload.estimators.protocol import Estimator
from wheelload.models import Vehicle

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


class UnknownMethodError(ValueError):
    """A method name that is not registered (the message lists the known ones)."""


class UnknownOptionError(TypeError):
    """An option passed to :func:`build` that the method's constructor does not take."""


@dataclass(frozen=True, kw_only=True)
class MethodInfo:
    """One registered method: its name, a one-line description, its source and its builder.

    ``build(vehicle)``; a method with ``model_choice`` also takes
    ``build(vehicle, suspension=SuspensionModel...)``.
    """

    name: str
    description: str
    reference: str
    build: Callable[..., Estimator]
    model_choice: bool = False

    def __post_init__(self) -> None:
        if not self.name or any(c.isspace() or c == "," for c in self.name):
            raise ValueError(
                f"method name must be non-empty without spaces or commas: {self.name!r}"
            )
        if not callable(self.build):
            raise TypeError(f"method {self.name}: build must be callable")


def _kf(vehicle: Vehicle, **options) -> Estimator:
    from wheelload.estimators.kf.two_stage import TwoStageKF

    return TwoStageKF(vehicle, **options)


def _projection(weighting_name: str) -> Callable[[Vehicle], Estimator]:
    def build(vehicle: Vehicle, **options) -> Estimator:
        from wheelload.estimators.kf.projection import ProjectionKF, Weighting

        return ProjectionKF(vehicle, weighting=Weighting[weighting_name], **options)

    return build


def _mhe(vehicle: Vehicle, **options) -> Estimator:
    from wheelload.estimators.mhe.method import MheMethod

    return MheMethod(vehicle, **options)


CORE = (
    MethodInfo(
        name="kf",
        description="two-stage physics-constrained KF: suspension update + soft equilibrium",
        reference="Siegloff & Choi §III, eq. 12-25 (method A)",
        build=_kf,
    ),
    MethodInfo(
        name="projection-mp",
        description="KF with exact projection onto the equilibrium, W = P^-1",
        reference="Simon & Chia 2002; Siegloff & Choi eq. 14-16",
        build=_projection("MAXIMUM_PROBABILITY"),
    ),
    MethodInfo(
        name="projection-ls",
        description="KF with exact projection onto the equilibrium, W = I",
        reference="Simon & Chia 2002; Siegloff & Choi eq. 14-16",
        build=_projection("LEAST_SQUARES"),
    ),
    MethodInfo(
        name="mhe",
        description="moving-horizon estimator N=10, soft equilibrium, OSQP",
        reference="Rao, Rawlings & Lee 2001; Siegloff & Choi eq. 12-17",
        build=_mhe,
    ),
)


def _family_infos() -> list[MethodInfo]:
    infos = []
    for module in FAMILY_MODULES:
        full = f"{FAMILY_PACKAGE}.{module}"
        try:
            loaded = importlib.import_module(full)
        except ModuleNotFoundError as error:
            if error.name == full:
                continue  # not installed in this build
            raise
        info = loaded.INFO
        if not isinstance(info, MethodInfo):
            raise TypeError(f"{full}.INFO must be a MethodInfo, got {type(info).__name__}")
        infos.append(info)
    return infos


@functools.cache
def methods() -> dict[str, MethodInfo]:
    """Every registered method by name, in table order (core first)."""
    table: dict[str, MethodInfo] = {}
    for info in (*CORE, *_family_infos()):
        if info.name in table:
            raise ValueError(f"method name {info.name!r} is registered twice")
        table[info.name] = info
    return table


def method(name: str) -> MethodInfo:
    """The registered method ``name`` (exact, else case-insensitive match)."""
    table = methods()
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
    ``options`` go to the method's constructor as keyword arguments (the KF's
    ``static``, ``step``, ``guard_settings``, ...); one the method does not take
    raises :class:`UnknownOptionError` naming the method and the option.
    """
    info = method(name)
    try:
        if info.model_choice:
            return info.build(vehicle, suspension=suspension, **options)
        return info.build(vehicle, **options)
    except TypeError as error:
        unknown = [key for key in options if f"'{key}'" in str(error)]
        if unknown and "unexpected keyword argument" in str(error):
            raise UnknownOptionError(
                f"method {info.name!r} takes no option {unknown[0]!r}"
            ) from None
        raise
