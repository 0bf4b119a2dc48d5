r"""Method A, the two-stage KF (Siegloff & Choi §III, eq. 12-25), and its projection variants.

The registry's entries (``INFO``, in table order) of the core Kalman filters:
the two-stage KF with its soft equilibrium update, and the projection KFs that
replace that update by an exact projection onto :math:`A x = b` (Simon & Chia
2002) with :math:`W = P^{-1}` or :math:`W = I`. The builders import the filters
where used, so that listing the methods stays fast.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.protocol import Estimator, MethodInfo
from wheelload.models import Vehicle


@dataclass(frozen=True, kw_only=True)
class ProjectionOptions:
    """Options of the projection KFs (``build("projection-mp", vehicle, **options)``)."""

    static: np.ndarray | None = None  # static loads FL..RR [N]; None: the vehicle file's
    guard_settings: GuardSettings | None = None  # input guards; None: the vehicle file's
    check_file: bool = True  # check the vehicle file against the log (model errors)


@dataclass(frozen=True, kw_only=True)
class KfOptions(ProjectionOptions):
    """Options of the two-stage KF (``build("kf", vehicle, **options)``)."""

    step: ca.Function | None = None  # the step Function; None: step_function()'s default
    sample_interval: float | None = None  # nominal interval [s] of the noise; None: each dt


def build_kf(vehicle: Vehicle, **options) -> Estimator:
    """:class:`~wheelload.estimators.kf.two_stage.TwoStageKF` with the constructor's options."""
    from wheelload.estimators.kf.two_stage import TwoStageKF

    return TwoStageKF(vehicle, **options)


def projection_builder(weighting_name: str) -> Callable[..., Estimator]:
    """A builder of :class:`~wheelload.estimators.kf.projection.ProjectionKF` with one weighting."""

    def build(vehicle: Vehicle, **options) -> Estimator:
        from wheelload.estimators.kf.projection import ProjectionKF, Weighting

        return ProjectionKF(vehicle, weighting=Weighting[weighting_name], **options)

    return build


#: Table order: the KF, then its projection variants.
INFO = (
    MethodInfo(
        name="kf",
        description="two-stage physics-constrained KF: suspension update + soft equilibrium",
        reference="Siegloff & Choi §III, eq. 12-25 (method A)",
        build=build_kf,
        options=KfOptions,
        compiled_batch=True,
    ),
    MethodInfo(
        name="projection-mp",
        description="KF with exact projection onto the equilibrium, W = P^-1",
        reference="Simon & Chia 2002; Siegloff & Choi eq. 14-16",
        build=projection_builder("MAXIMUM_PROBABILITY"),
        options=ProjectionOptions,
    ),
    MethodInfo(
        name="projection-ls",
        description="KF with exact projection onto the equilibrium, W = I",
        reference="Simon & Chia 2002; Siegloff & Choi eq. 14-16",
        build=projection_builder("LEAST_SQUARES"),
        options=ProjectionOptions,
    ),
)
