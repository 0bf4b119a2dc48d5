r"""Method D, suspension-only: the pseudo-measurement alone (Siegloff & Choi §IV-B).

.. math:: \hat F_{z,i} = z_i(d, v) = F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i

the suspension model of §II-B (eq. 3-9, :func:`wheelload.models.travel_function`)
evaluated sample by sample, without filtering or constraint. Adaptation: a
wheel whose travel or rate (or the anti-roll-bar partner's travel) is
missing keeps its previous estimate and is flagged. No standard deviation.
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
from wheelload.models import ModelParameters, Vehicle, travel_function


@functools.cache
def suspension_only_step() -> ca.Function:
    """Step: state = last loads; loads = the suspension model where its inputs are valid."""
    sym = step_symbols(4, 0)
    z = travel_function()(sym.d, sym.v, sym.p_vector)
    mask = sym.mask(z)
    loads = hold(mask, z, sym.s)
    return step_function("wheelload_suspension_only_step", sym, loads, loads, ca.SX.zeros(4), mask)


class SuspensionOnly(StepMethod):
    """Method D: the suspension pseudo-measurement as the estimate (module docstring)."""

    name = "D suspension-only"
    has_std = False

    def __init__(self, vehicle: Vehicle) -> None:
        parameters = ModelParameters.from_vehicle(vehicle)
        super().__init__(
            suspension_only_step(),
            parameters.vector(),
            np.zeros(0),
            np.array(parameters.static(), float),
        )


INFO = MethodInfo(
    name="D",
    description="suspension-only: the suspension pseudo-measurement alone, no filter",
    reference="Siegloff & Choi §IV-B method D; §II-B eq. 3-9",
    build=SuspensionOnly,
)
