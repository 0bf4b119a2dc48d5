r"""Which vehicle model a family method uses: the KF's full model or the paper's bare one.

A fair comparison of estimators gives each the same vehicle model, so that
the ranking measures the estimators, not the models. Every family method
that uses the suspension pseudo-measurement or the rigid-body equilibrium
therefore takes them from the same CasADi Functions as the two-stage KF
(:func:`wheelload.models.suspension_function`,
:func:`wheelload.models.equilibrium_function`), with the model terms the
vehicle file's ``[model]`` section switches on, gated per sample by the
validity of their inputs exactly as in the KF (:func:`wheelload.models.gates_function`):
:attr:`SuspensionModel.FULL`, the default.

:attr:`SuspensionModel.PAPER` keeps the source papers' bare model: the
spring, damper and anti-roll-bar pseudo-measurement of eq. 9
(:func:`wheelload.models.travel_function`) and the body-axis equilibrium of
eq. 15-16 (:func:`wheelload.models.paper_equilibrium_function`), every
model term off whatever the vehicle file says. It reproduces the methods as
published (``wheelload compare --suspension paper``).

Either way an update's availability is decided by the paper model's inputs
(travel and rate for a wheel's pseudo-measurement; specific force and speed
for the equilibrium rows), as in the KF: a missing optional input (body
rates, hub accelerometers) drops only the term that needs it.
"""

from __future__ import annotations

import casadi as ca

from wheelload.estimators.protocol import SuspensionModel
from wheelload.models import (
    GATES,
    equilibrium_function,
    gates_function,
    paper_equilibrium_function,
    suspension_function,
    travel_function,
)
from wheelload.models.conventions import WHEELS
from wheelload.models.input_validity import dependency_mask
from wheelload.models.inputs import TRAVEL, TRAVEL_RATE, input_index

_UNSPRUNG_GATES = tuple(GATES.index(f"unsprung_{w}") for w in WHEELS)
_TRAVEL_INDEX = input_index(TRAVEL)
_RATE_INDEX = input_index(TRAVEL_RATE)


def _gates(valid, p_vector, unsprung_inertia: bool) -> ca.SX:
    gates = gates_function()(valid, p_vector)[0]
    if unsprung_inertia:
        return gates
    keep = ca.DM.ones(len(GATES))
    for i in _UNSPRUNG_GATES:
        keep[i] = 0.0
    return gates * keep


def _with_travel(u, d, v) -> ca.SX:
    entries = [u[k] for k in range(u.shape[0])]
    for j, k in enumerate(_TRAVEL_INDEX):
        entries[k] = d[j]
    for j, k in enumerate(_RATE_INDEX):
        entries[k] = v[j]
    return ca.vertcat(*entries)


def suspension_loads(
    model: SuspensionModel, u, valid, p_vector, d=None, v=None, *, unsprung_inertia: bool = True
) -> ca.SX:
    r"""Pseudo-measured loads FL, FR, RL, RR :math:`z` of ``model``.

    ``u``: the sanitised inputs (:data:`~wheelload.models.INPUTS` order),
    ``valid`` their validity; ``d``, ``v`` replace the travel and rate of
    ``u`` (a method's own estimate of them, e.g. a sigma point).
    ``unsprung_inertia=False`` leaves out the hub accelerometers' unsprung
    term :math:`m_u (a_{hub} - g)` of the full model, for methods that
    estimate the unsprung inertia themselves (quarter-car observers).
    """
    d = u[0:4] if d is None else d
    v = u[4:8] if v is None else v
    if model is SuspensionModel.PAPER:
        return travel_function()(d, v, p_vector)
    gates = _gates(valid, p_vector, unsprung_inertia)
    return suspension_function()(_with_travel(u, d, v), gates, p_vector)


def equilibrium(model: SuspensionModel, u, valid, p_vector) -> tuple[ca.SX, ca.SX]:
    """``(A, b)`` of the rigid-body equilibrium :math:`A x = b` of ``model`` (eq. 15-16 + terms)."""
    if model is SuspensionModel.PAPER:
        return paper_equilibrium_function()(u[8:11], u[11], p_vector)
    return equilibrium_function()(u, _gates(valid, p_vector, True), p_vector)


def equilibrium_residual(model: SuspensionModel, u, valid, p_vector, loads) -> tuple[ca.SX, ca.SX]:
    r"""Residual :math:`b - A \hat x` of ``loads`` in ``model``'s equilibrium, and its availability.

    The residual is 0 where a specific-force axis or the speed is missing; the
    availability is 1 where all four are valid.
    """
    A, b = equilibrium(model, u, valid, p_vector)
    available = valid[8] * valid[9] * valid[10] * valid[11]
    return ca.if_else(available, b - ca.mtimes(A, loads), ca.DM.zeros(3)), available


def suspension_mask(u_raw, valid, p_vector) -> ca.SX:
    """1 per wheel whose pseudo-measurement's paper inputs (travel, rate, bar partner) are valid."""
    return dependency_mask(travel_function()(u_raw[0:4], u_raw[4:8], p_vector), u_raw, valid)


def equilibrium_mask(u_raw, valid, p_vector) -> ca.SX:
    """1 per equilibrium row whose paper inputs (specific force, speed) are valid."""
    b = paper_equilibrium_function()(u_raw[8:11], u_raw[11], p_vector)[1]
    return dependency_mask(b, u_raw, valid)
