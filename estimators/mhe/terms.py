r"""The quadratic-program terms one sample adds to the MHE window, as one CasADi Function.

For sample :math:`j` with suspension pseudo-measurement :math:`z_j` (Siegloff
& Choi eq. 13) and equilibrium :math:`A x_j = b_j` (eq. 14-17), weights
:math:`W_s = \mathrm{diag}(m_s\,dt/r_{s,j})`, :math:`W_c = \mathrm{diag}(m_c\,dt/r_{c,j})`
(:math:`m`: the filter's dependency masks, 0 where an input the row needs is
missing; :math:`r_{s,j}, r_{c,j}`: the rows' noise densities at sample :math:`j`,
:math:`R\,\Delta t` of :mod:`wheelload.models.measurement_noise`, the filter's
Function, so constant :math:`r_s, r_c` with the default zero input-dependent
densities) and random-walk weight :math:`w_q = 1/(q\,dt)`:

.. math::
    \text{soft:}\quad H_j = W_s + A^\top W_c A, \quad g_j = -(W_s z_j + A^\top W_c b_j)

    \text{hard:}\quad x_j = \bar x_j + n\,\omega_j, \quad
    \bar x_j = A^+ \tilde b_j, \quad H_j = n^\top W_s n, \quad
    g_j = n^\top W_s (\bar x_j - z_j)

where :math:`\tilde b_j` takes :math:`A x_{ref}` on rows whose inputs are
missing, and the bounds :math:`F_{min} \le x_j \le F_{max}` become an interval
of the warp amplitude :math:`\omega_j` (collapsed to its midpoint when empty).
All outputs are in the QP's units: loads in kN, cost scaled by ``cost``.

The Python MHE maps this Function over a log (``.map(n)``) or calls it once
per :meth:`step`; the embedded C MHE calls its generated code per sample.

Example
-------
>>> f = terms_function(Constraint.SOFT, null=n, pinv=A_pinv, lower_load=0.0, upper_load=inf)
>>> H, g, link, xp, lower, upper, b, used = f(u, u_valid, dt, x_ref, p, tuning, cost)
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from wheelload.estimators.guards import plausibility
from wheelload.estimators.guards import settings as guard
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kf.model_rows import model_rows
from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.mhe.settings import Constraint
from wheelload.models import (
    INPUTS,
    ModelParameters,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.input_validity import sanitise
from wheelload.models.inputs import SPECIFIC_FORCE, TRAVEL, input_index
from wheelload.models.measurement_noise import DENSITIES, measurement_noise_function
from wheelload.models.terms import with_entries

TERMS_NAME = "wheelload_mhe_terms"
LOAD_SCALE = 1000.0  # N: the QP's variables are in kN
TERMS_INPUTS = ["u", "u_valid", "dt", "x_ref", "p", "tuning", "cost"]
TERMS_OUTPUTS = ["H", "g", "link", "xp", "lower", "upper", "b", "used"]


def warp_interval(xp, null: np.ndarray, lower_load: float, upper_load: float):
    r"""Interval of :math:`\omega` with ``lower_load <= xp + null * omega <= upper_load``.

    An empty interval (no bounded loads satisfy the equilibrium) collapses to
    its midpoint; the caller clips the loads to the bounds.
    """
    ends = [((lower_load - xp[i]) / null[i], (upper_load - xp[i]) / null[i]) for i in range(4)]
    ordered = [(a, c) if null[i] > 0 else (c, a) for i, (a, c) in enumerate(ends)]
    low = ca.mmax(ca.vertcat(*[a for a, _ in ordered]))
    high = ca.mmin(ca.vertcat(*[c for _, c in ordered]))
    middle = 0.5 * (low + high)
    empty = low > high
    return ca.if_else(empty, middle, low), ca.if_else(empty, middle, high)


def plausible_inputs(u_raw, valid, p, tuning) -> ca.SX:
    r"""``valid`` times the KF's plausibility of each input (:func:`.plausibility.plausible`).

    The ranges are the filter's guard settings in ``tuning`` (:math:`|a| \le a_{max}`,
    :math:`|v_x| \le v_{max}`, :math:`|d_i| \le c\,m g / k_i`, :math:`|\dot d_i| \le
    \dot d_{max}`, hub accelerations): an input the KF would not take is missing for the
    window too, so its rows are dropped and flagged (a 1e30 or a spike off the physical
    range never reaches the QP). The same symbolic function as the KF's step, so the Python
    MHE and its generated C share it.
    """
    settings = guard.unpack(TUNING.values(tuning, GuardSettings.names()))
    in_range = plausibility.plausible_for(sanitise(u_raw, valid), p, settings)
    return valid * in_range


def row_densities(u_raw, valid, tuning) -> tuple[ca.SX, ca.SX]:
    r"""The rows' white-noise densities ``(r_s[4], r_c[3])`` of one sample.

    :math:`R\,\Delta t` of :func:`~wheelload.models.measurement_noise.measurement_noise_function`
    (evaluated at :math:`\Delta t = 1`): the filter's measurement noise, input-dependent
    with the vehicle file's optional densities, :math:`r_s`, :math:`r_c` bit for bit without.
    The window weighs a row by :math:`dt / r` with the sample's own interval.
    """
    densities = TUNING.values(tuning, DENSITIES)
    return measurement_noise_function()(sanitise(u_raw, valid), valid, densities, 1.0)


def terms_function(
    constraint: Constraint,
    *,
    null: np.ndarray,
    pinv: np.ndarray,
    lower_load: float,
    upper_load: float,
    suspension: ca.Function | None = None,
    equilibrium: ca.Function | None = None,
) -> ca.Function:
    """``wheelload_mhe_terms(u, u_valid, dt, x_ref, p, tuning, cost) -> (H, g, link, xp, lower,
    upper, b, used)``, the terms of the module docstring.

    ``null`` and ``pinv`` are the unit null vector and pseudo-inverse of the
    vehicle's equilibrium matrix; ``lower_load``/``upper_load`` [N] the load
    bounds (infinite when unbounded); ``x_ref`` [N] the loads whose
    :math:`A x` stands in for equilibrium rows with missing inputs (hard
    only). ``used`` is the 7 masks (4 suspension, 3 equilibrium rows), then 1 - the
    4 dropped-term indicators (``StepFlag.update_flags`` order).
    """
    if not isinstance(constraint, Constraint):
        raise TypeError(f"constraint must be a Constraint, got {constraint!r}")
    suspension = suspension or suspension_function()
    equilibrium = equilibrium or equilibrium_function()
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    x_ref = ca.SX.sym("x_ref", 4)
    p = ca.SX.sym("p", len(ModelParameters.names()))
    tuning = ca.SX.sym("tuning", TUNING.size)
    cost = ca.SX.sym("cost")

    inputs = [u_raw, valid, dt, x_ref, p, tuning, cost]
    valid = plausible_inputs(u_raw, valid, p, tuning)
    z, A, b, mask_s, mask_c, dropped = model_rows(suspension, equilibrium, u_raw, valid, p)
    r_s, r_c = row_densities(u_raw, valid, tuning)
    w_s = mask_s * dt / r_s
    w_c = mask_c * dt / r_c
    link = cost * LOAD_SCALE**2 / (TUNING.value(tuning, "process_noise_density") * dt)
    n = ca.DM(null)
    if constraint is Constraint.SOFT:
        H = ca.diag(w_s) + ca.mtimes([A.T, ca.diag(w_c), A])
        g = -(w_s * z + ca.mtimes(A.T, w_c * b))
        xp = ca.DM.zeros(4)
        lower = ca.DM.ones(4) * lower_load
        upper = ca.DM.ones(4) * upper_load
    else:
        b_kept = ca.vertcat(
            *[ca.if_else(mask_c[i], b[i], ca.mtimes(A[i, :], x_ref)) for i in range(3)]
        )
        xp = ca.mtimes(ca.DM(pinv), b_kept)
        H = ca.dot(n, w_s * n)
        g = ca.dot(n, w_s * (xp - z))
        if np.isfinite(lower_load) or np.isfinite(upper_load):
            lower, upper = warp_interval(xp, null, lower_load, upper_load)
        else:
            lower, upper = ca.DM(-np.inf), ca.DM(np.inf)
    outputs = [
        cost * LOAD_SCALE**2 * ca.reshape(H, -1, 1),
        cost * LOAD_SCALE * g,
        link,
        xp,
        lower / LOAD_SCALE,
        upper / LOAD_SCALE,
        b,
        ca.vertcat(mask_s, mask_c, 1 - dropped),
    ]
    dense = [ca.densify(ca.SX(output)) for output in outputs]  # C reads every entry
    return ca.Function(TERMS_NAME, inputs, dense, TERMS_INPUTS, TERMS_OUTPUTS)


RESIDUAL_NAME = "wheelload_mhe_residual_rows"


def residual_function(
    suspension: ca.Function | None = None, equilibrium: ca.Function | None = None
) -> ca.Function:
    r"""``wheelload_mhe_residual_rows(u, u_valid, dt, p, tuning) -> (z, Jd, Ba, ls, lc)``.

    The pseudo-measurement :math:`z` [N], its Jacobian :math:`J_d = \partial z /
    \partial d`, the Jacobian :math:`B_a = \partial b / \partial (a_x, a_y)` of the
    equilibrium right-hand side, and the rows' square-root weights
    :math:`\sqrt{m\,dt/r}` (masked like the filter's updates; :func:`row_densities`) used by the
    robust and bias-state window (:mod:`wheelload.estimators.mhe.window`).
    """
    suspension = suspension or suspension_function()
    equilibrium = equilibrium or equilibrium_function()
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", len(ModelParameters.names()))
    tuning = ca.SX.sym("tuning", TUNING.size)
    inputs = [u_raw, valid, dt, p, tuning]
    valid = plausible_inputs(u_raw, valid, p, tuning)
    z, _, b, mask_s, mask_c, _ = model_rows(suspension, equilibrium, u_raw, valid, p)
    gates, _ = gates_function()(valid, p)
    u = sanitise(u_raw, valid)
    d, acc = ca.SX.sym("d", 4), ca.SX.sym("acc", 3)
    travel, axes = input_index(TRAVEL), input_index(SPECIFIC_FORCE)
    d_now = ca.vertcat(*[u[k] for k in travel])
    acc_now = ca.vertcat(*[u[k] for k in axes])
    Jd = ca.substitute(ca.jacobian(suspension(with_entries(u, travel, d), gates, p), d), d, d_now)
    b_sym = equilibrium(with_entries(u, axes, acc), gates, p)[1]
    Ba = ca.substitute(ca.jacobian(b_sym, acc[0:2]), acc, acc_now)
    r_s, r_c = row_densities(u_raw, valid, tuning)
    ls = ca.sqrt(mask_s * dt / r_s)
    lc = ca.sqrt(mask_c * dt / r_c)
    outputs = [ca.densify(ca.SX(o)) for o in (z, Jd, Ba, ls, lc)]
    return ca.Function(
        RESIDUAL_NAME, inputs, outputs,
        ["u", "u_valid", "dt", "p", "tuning"], ["z", "Jd", "Ba", "ls", "lc"],
    )  # fmt: skip
