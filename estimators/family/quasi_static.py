r"""Method C, quasi-static: static loads plus rigid-body load transfer (Siegloff & Choi §IV-B).

.. math:: \hat x = z_0 + K A^\top (A K A^\top)^{-1} (b - A z_0)

(:func:`wheelload.models.load_transfer.quasi_static_transfer`): the loads of
a rigid body on its suspension in steady acceleration, exact equilibrium
:math:`A \hat x = b`, the roll moment split by the suspension's stiffness
:math:`K = \partial z / \partial d`. No suspension travel is used: the
model is evaluated at the static position (:math:`d = v = 0`).

- Full model (default, :mod:`~wheelload.estimators.family.suspension_model`):
  :math:`z_0` is the KF's pseudo-measurement at the static position (static
  loads plus the load the links carry, roll centres and anti-pitch, and the
  unsprung inertia of the hub accelerometers), :math:`K` its Jacobian there,
  :math:`A, b` the KF's equilibrium with the vehicle file's terms (IMU lever
  arm and mounting, body inertia, drag, unsprung heave; the road-frame
  rotation needs the travel and is therefore zero).
- Paper model: :math:`z_0 = x_0` the static loads, :math:`K` of eq. 9,
  :math:`A, b` of eq. 15-16 (specific force, lift, drag)
  (:func:`wheelload.models.load_transfer.quasi_static_function`).

Adaptations: the paper anchors the transfer to static axle loads without
naming its split; ours is the suspension's own. A sample with a missing
accelerometer or speed channel keeps the previous estimate and is flagged.
No standard deviation. This is a strengthened C: it meets the equilibrium rows
exactly (vertical acceleration, lift and drag included) and splits the roll moment
by the suspension's Jacobian.

``C-paper`` is the paper's C as its text states it: static loads plus the
rigid-body transfer of :math:`f_x, f_y` with the lateral split fixed at the static
axle loads (:func:`wheelload.models.load_transfer.static_transfer_loads`); no
vertical acceleration, aerodynamics or suspension; the same on either vehicle
model (it has none of the model's terms).
"""

from __future__ import annotations

import functools

import casadi as ca

from wheelload.estimators.family.flat_step import StepSymbols, hold, step_function, step_symbols
from wheelload.estimators.family.step_method import FamilyMethod
from wheelload.estimators.family.suspension_model import equilibrium, suspension_loads
from wheelload.estimators.protocol import DEFAULT_MODEL, MethodInfo, SuspensionModel
from wheelload.models.inputs import TRAVEL, TRAVEL_RATE, input_index
from wheelload.models.load_transfer import (
    quasi_static_function,
    quasi_static_transfer,
    static_transfer_function,
)

_TRAVEL = input_index(TRAVEL + TRAVEL_RATE)


def full_quasi_static_loads(sym: StepSymbols) -> ca.SX:
    """:math:`\\hat x` of the full model at the static position (module docstring)."""
    u = ca.vertcat(*[0.0 if k in _TRAVEL else sym.u[k] for k in range(sym.u.shape[0])])
    valid = ca.vertcat(*[1.0 if k in _TRAVEL else sym.valid[k] for k in range(sym.u.shape[0])])
    model = SuspensionModel.FULL
    d = ca.SX.sym("d", 4)
    z = suspension_loads(model, u, valid, sym.p_vector, d=d, v=ca.DM.zeros(4))
    z0 = ca.substitute(z, d, ca.DM.zeros(4))
    K = ca.substitute(ca.jacobian(z, d), d, ca.DM.zeros(4))
    A, b = equilibrium(model, u, valid, sym.p_vector)
    return quasi_static_transfer(z0, K, A, b)


@functools.cache
def quasi_static_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step: state = last loads; loads = quasi-static loads where acc and vx are valid."""
    sym = step_symbols(4, 0)
    if model is SuspensionModel.PAPER:
        x = quasi_static_function()(sym.acc, sym.vx, sym.p_vector)
    else:
        x = full_quasi_static_loads(sym)
    paper = quasi_static_function()(sym.acc, sym.vx, sym.p_vector)
    ok = ca.mmin(sym.mask(paper))
    loads = hold(ca.repmat(ok, 4, 1), x, sym.s)
    return step_function(
        "wheelload_quasi_static_step", model, sym, loads, loads, ca.SX.zeros(4), ca.DM.ones(4)
    )


@functools.cache
def static_transfer_step(model: SuspensionModel = DEFAULT_MODEL) -> ca.Function:
    """Step of ``C-paper``: state = last loads; loads = static loads plus rigid transfer
    where the accelerometers are valid (``model`` only names the Function)."""
    sym = step_symbols(4, 0)
    x = static_transfer_function()(sym.acc, sym.p_vector)
    ok = ca.mmin(sym.mask(x))
    loads = hold(ca.repmat(ok, 4, 1), x, sym.s)
    return step_function(
        "wheelload_static_transfer_step", model, sym, loads, loads, ca.SX.zeros(4), ca.DM.ones(4)
    )


class QuasiStatic(FamilyMethod):
    """Method C: quasi-static rigid-body load transfer (module docstring)."""

    name = "C quasi-static"
    has_std = False

    def build_step(self) -> ca.Function:
        return quasi_static_step(self.suspension)


class StaticTransfer(FamilyMethod):
    """Method C as the paper states it (module docstring: ``C-paper``)."""

    name = "C paper-faithful"
    has_std = False

    def build_step(self) -> ca.Function:
        return static_transfer_step(self.suspension)


INFO = (
    MethodInfo(
        name="C",
        description="quasi-static (strengthened): static loads moved onto the exact equilibrium "
        "along the suspension stiffness",
        reference="Siegloff & Choi §IV-B method C; equilibrium eq. 14-16",
        build=QuasiStatic,
        model_choice=True,
    ),
    MethodInfo(
        name="C-paper",
        description="quasi-static as the paper states it: static loads + rigid transfer of "
        "ax, ay, split by the static axle loads",
        reference="Siegloff & Choi §IV-B method C",
        build=StaticTransfer,
        model_choice=False,
    ),
)
