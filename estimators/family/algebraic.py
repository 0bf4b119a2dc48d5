r"""Method B, algebraic normal loads after Alatorre et al. (Siegloff & Choi §IV-B, ref. [15]).

Body pitch and roll relative to the road from the travels, low-pass
filtered (first order, corner :data:`ATTITUDE_CUTOFF`),

.. math:: \bar\theta_k = \bar\theta_{k-1} + \alpha(\theta_k - \bar\theta_{k-1}), \quad
          \alpha = 1 - e^{-2\pi f_c \Delta t}

rotate the accelerometer's specific force into road-parallel axes, where
its components carry the road grade and bank as Alatorre's gravity terms
do; the loads are then Alatorre's algebraic load transfer with the lateral
transfer shared in proportion to the static axle loads
(:mod:`wheelload.models.load_transfer`):

.. math:: F_{FL,FR} = \tfrac{m}{2L}(l_r f_z - h f_x) \mp \tfrac{m h l_r}{L T_f} f_y, \quad
          F_{RL,RR} = \tfrac{m}{2L}(l_f f_z + h f_x) \mp \tfrac{m h l_f}{L T_r} f_y

Adaptations: the grade and bank are not estimated separately (the
road-frame specific force contains them); no aerodynamic terms (as in
[15]); whole-vehicle mass and CG. A missing travel holds the attitude
filter (flagged); a missing accelerometer channel holds the estimate. No
standard deviation.
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
from wheelload.models.load_transfer import algebraic_function, body_attitude_function

ATTITUDE_CUTOFF = 1.0  # Hz, "low-frequency suspension-derived pitch and roll"


@functools.cache
def algebraic_step() -> ca.Function:
    """Step: state = (loads[4], filtered pitch, filtered roll); constants = (cutoff,)."""
    sym = step_symbols(6, 1)
    held, angles = sym.s[0:4], sym.s[4:6]
    attitude = ca.vertcat(*body_attitude_function()(sym.d, sym.p_vector))
    travel_ok = sym.mask(attitude)
    alpha = 1.0 - ca.exp(-2.0 * ca.pi * sym.c[0] * sym.dt)
    filtered = hold(travel_ok, angles + alpha * (attitude - angles), angles)
    x = algebraic_function()(sym.acc, filtered[0], filtered[1], sym.p_vector)
    loads_ok = ca.mmin(sym.mask(sym.acc))
    loads = hold(ca.repmat(loads_ok, 4, 1), x, held)
    return step_function(
        "wheelload_algebraic_step",
        sym,
        ca.vertcat(loads, filtered),
        loads,
        ca.SX.zeros(4),
        sym.mask(sym.d),
    )


class Algebraic(StepMethod):
    """Method B: Alatorre-style algebraic load transfer (module docstring)."""

    name = "B algebraic"
    has_std = False

    def __init__(self, vehicle: Vehicle, *, attitude_cutoff: float = ATTITUDE_CUTOFF) -> None:
        if not attitude_cutoff > 0:
            raise ValueError(f"attitude_cutoff must be > 0 Hz, got {attitude_cutoff}")
        parameters = ModelParameters.from_vehicle(vehicle)
        super().__init__(
            algebraic_step(),
            parameters.vector(),
            np.array([attitude_cutoff]),
            np.array([*parameters.static(), 0.0, 0.0], float),
        )


INFO = MethodInfo(
    name="B",
    description="algebraic load transfer, road grade/bank via low-pass suspension pitch/roll",
    reference="Siegloff & Choi §IV-B method B; Alatorre, Victorino & Charara 2017",
    build=Algebraic,
)
