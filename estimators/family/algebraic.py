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

With the full model (the default,
:mod:`~wheelload.estimators.family.suspension_model`) the loads are the same
split of the KF's own equilibrium rows, whose road-frame term rotates the
specific force by the body attitude from the travels and tyre deflections
(instead of the low-pass attitude above) and which carries the IMU lever
arm, body inertia, lift and drag and the unsprung heave
(:func:`~wheelload.models.load_transfer.equilibrium_split`); with the paper
model, the formula above.

Adaptations: the grade and bank are not estimated separately (the
road-frame specific force contains them); no aerodynamic terms in the paper
variant (as in [15]); whole-vehicle mass and CG. A missing travel holds the attitude
filter (flagged); a missing accelerometer channel holds the estimate. No
standard deviation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.family.flat_step import (
    hold,
    model_equilibrium,
    step_function,
    step_symbols,
)
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models import Vehicle
from wheelload.models.body_attitude import body_attitude_function
from wheelload.models.load_transfer import algebraic_function, equilibrium_split

ATTITUDE_CUTOFF = 1.0  # Hz, "low-frequency suspension-derived pitch and roll"


@functools.cache
def algebraic_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state = (loads[4], filtered pitch, filtered roll); constants = (cutoff,)."""
    sym = step_symbols(6, 1)
    held, angles = sym.s[0:4], sym.s[4:6]
    attitude = ca.vertcat(*body_attitude_function()(sym.d, sym.p_vector))
    travel_ok = sym.mask(attitude)
    alpha = 1.0 - ca.exp(-2.0 * ca.pi * sym.c[0] * sym.dt)
    filtered = hold(travel_ok, angles + alpha * (attitude - angles), angles)
    A, b, mask_c = model_equilibrium(model, sym)
    if model is SuspensionModel.PAPER:
        x = algebraic_function()(sym.acc, filtered[0], filtered[1], sym.p_vector)
    else:
        x = equilibrium_split(b, sym.p)
    loads_ok = ca.mmin(sym.mask(sym.acc))
    loads = hold(ca.repmat(loads_ok, 4, 1), x, held)
    return step_function(
        "wheelload_algebraic_step",
        model,
        sym,
        ca.vertcat(loads, filtered),
        loads,
        ca.SX.zeros(4),
        sym.mask(sym.d),
        (A, b, mask_c),
    )


class Algebraic(FamilyMethod):
    """Method B: Alatorre-style algebraic load transfer (module docstring)."""

    name = "B algebraic"
    has_std = False

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        attitude_cutoff: float = ATTITUDE_CUTOFF,
        suspension: SuspensionModel = DEFAULT_MODEL,
    ) -> None:
        if not attitude_cutoff > 0:
            raise ValueError(f"attitude_cutoff must be > 0 Hz, got {attitude_cutoff}")
        self.attitude_cutoff = attitude_cutoff
        super().__init__(vehicle, suspension=suspension)

    def build_step(self) -> ca.Function:
        return algebraic_step(self.suspension)

    def initial_arrays(self) -> tuple[np.ndarray, ...]:
        return (np.array([*self.parameters.static(), 0.0, 0.0], float),)

    def constants(self) -> np.ndarray:
        return np.array([self.attitude_cutoff])


@dataclass(frozen=True, kw_only=True)
class AlgebraicOptions:
    """Options of method B (``build("B", vehicle, **options)``)."""

    attitude_cutoff: float = ATTITUDE_CUTOFF  # corner [Hz] of the pitch/roll low-pass


INFO = MethodInfo(
    name="B",
    description="algebraic load transfer, road grade/bank via low-pass suspension pitch/roll",
    reference="Siegloff & Choi §IV-B method B; Alatorre, Victorino & Charara 2017",
    build=Algebraic,
    options=AlgebraicOptions,
    model_choice=True,
)
