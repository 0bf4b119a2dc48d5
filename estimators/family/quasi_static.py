r"""Method C, quasi-static: static loads plus rigid-body load transfer (Siegloff & Choi §IV-B).

.. math:: \hat x = x_0 + K A^\top (A K A^\top)^{-1} (b - A x_0)

with the static loads :math:`x_0`, the equilibrium :math:`A, b` of eq. 15-16
(specific force, aerodynamic lift and drag) and the suspension stiffness
:math:`K = \partial z/\partial d` of eq. 9
(:func:`wheelload.models.load_transfer.quasi_static_function`). It is the
load distribution of a rigid body on its springs and anti-roll bars in
steady acceleration: exact equilibrium, roll moment split by roll stiffness.
Adaptations: the paper anchors the transfer to static axle loads without
naming its split; ours is the suspension's own, and it uses the same
equilibrium vector as the KF (so it includes lift, drag and :math:`a_z`).
No suspension travel is used. A sample with a missing accelerometer or
speed channel keeps the previous estimate and is flagged. No standard
deviation.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from wheelload.estimators.family.step_method import (
    StepMethod,
    hold,
    step_function,
    step_symbols,
)
from wheelload.estimators.registry import MethodInfo
from wheelload.models import ModelParameters, Vehicle
from wheelload.models.load_transfer import quasi_static_function


@functools.cache
def quasi_static_step() -> ca.Function:
    """Step: state = last loads; loads = quasi-static loads where acc and vx are valid."""
    sym = step_symbols(4, 0)
    x = quasi_static_function()(sym.acc, sym.vx, sym.p_vector)
    ok = ca.mmin(sym.mask(x))
    loads = hold(ca.repmat(ok, 4, 1), x, sym.s)
    return step_function(
        "wheelload_quasi_static_step", sym, loads, loads, ca.SX.zeros(4), ca.DM.ones(4)
    )


class QuasiStatic(StepMethod):
    """Method C: quasi-static rigid-body load transfer (module docstring)."""

    name = "C quasi-static"
    has_std = False

    def __init__(self, vehicle: Vehicle) -> None:
        parameters = ModelParameters.from_vehicle(vehicle)
        super().__init__(
            quasi_static_step(),
            parameters.vector(),
            np.zeros(0),
            np.array(parameters.static(), float),
        )


INFO = MethodInfo(
    name="C",
    description="quasi-static: static loads + rigid-body load transfer split by roll stiffness",
    reference="Siegloff & Choi §IV-B method C; equilibrium eq. 14-16",
    build=QuasiStatic,
)
