r"""Method D, suspension-only: the pseudo-measurement alone (Siegloff & Choi §IV-B).

.. math:: \hat F_{z,i} = z_i(d, v) = F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i

the suspension model of §II-B evaluated sample by sample, without filtering
or constraint. By default the KF's own pseudo-measurement with the vehicle
file's model terms (:func:`wheelload.models.suspension_function`: link and
tyre-force loads, stops, unsprung inertia); ``suspension=SuspensionModel.PAPER``
gives the paper's eq. 3-9 alone (:mod:`~wheelload.estimators.family.suspension_model`).
Adaptation: a wheel whose travel or rate (or the anti-roll-bar partner's
travel) is missing keeps its previous estimate and is flagged. No standard
deviation.
"""

from __future__ import annotations

import functools

import casadi as ca

from wheelload.estimators.family.flat_step import hold, step_function, step_symbols
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import suspension_loads, suspension_mask
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel


@functools.cache
def suspension_only_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state = last loads; loads = the suspension model where its inputs are valid."""
    sym = step_symbols(4, 0)
    z = suspension_loads(model, sym.u, sym.valid, sym.p_vector)
    mask = suspension_mask(sym.u_raw, sym.valid, sym.p_vector) * sym.dt_ok
    loads = hold(mask, z, sym.s)
    return step_function(
        "wheelload_suspension_only_step", model, sym, loads, loads, ca.SX.zeros(4), mask
    )


class SuspensionOnly(FamilyMethod):
    """Method D: the suspension pseudo-measurement as the estimate (module docstring)."""

    name = "D suspension-only"
    has_std = False

    def build_step(self) -> ca.Function:
        return suspension_only_step(self.suspension)


INFO = MethodInfo(
    name="D",
    description="suspension-only: the suspension pseudo-measurement alone, no filter",
    reference="Siegloff & Choi §IV-B method D; §II-B eq. 3-9",
    build=SuspensionOnly,
    model_choice=True,
)
