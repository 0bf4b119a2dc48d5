r"""Online payload mass and CG: a companion Kalman filter inside the filter step.

State :math:`\vartheta = [\Delta m, S_x, S_y, S_z]`, the payload's mass and first moments
about the file's CG (:mod:`wheelload.models.loaded_vehicle`), a random walk whose density
is ``drift_density`` while driving and ``standstill_density`` while the car stands
(:math:`|v_x|` below ``standstill_speed``: people and luggage get in at a stop); the
moments' densities are the mass's times the squared prior position spreads. Travel is
measured from the file's reference state, so the suspension pseudo-measurement
:math:`z` sees the payload while the equilibrium rows see the file's masses. The
measurement is the equilibrium at the pseudo-measured loads,

.. math:: r(\vartheta) = A(p_\vartheta)\, z - b(u;\, p_\vartheta) = 0 + w, \quad
          w \sim N(0, \mathrm{diag}(r_\vartheta) / \Delta t_{nom}),

linearised at the prediction (an extended Kalman update, one row at a time, each gated
at :math:`y^2 \le g\,S`), with each row's :math:`r_\vartheta` times
:math:`(1 + (a_x^2 + a_y^2) / a_s^2)^2`: the model's mismatch grows with the square of the
load transfer (the second-order terms, :math:`a_y \sin\phi`, the links). The vertical
row, which those terms bias in a turn, has the smaller scale :math:`a_s`; the moment rows
keep the turns in which they see the CG height (estimated only when its prior spread is
set: by default the payload sits at the CG's height). The residual
density covers that mismatch, which is coloured, so the estimate averages over many
seconds; a sensor bias the equilibrium can
see (:math:`a_z`, a lateral or longitudinal offset) is absorbed as a small mass or CG
shift, and the loads' rows stay consistent with the springs. The prior is
:math:`\Delta m \sim N(0, \sigma_m^2)`, :math:`S \sim N(0, \sigma_m^2 \sigma_x^2)`; the
covariance never exceeds it. The state (4) and its covariance (4 x 4) are carried in the
step's monitor state ``m`` (:data:`~wheelload.estimators.guards.monitor_state.PAYLOAD`).
"""

from __future__ import annotations

import dataclasses

import casadi as ca

from wheelload.estimators.kernels.kalman import sequential_update_innovations, symmetrise
from wheelload.estimators.kf.tuning import PAYLOAD
from wheelload.models import GATES, INPUTS, ModelParameters, equilibrium_function
from wheelload.models.loaded_vehicle import (
    PAYLOAD_STATES,
    loaded_parameters_function,
    mass_properties,
)

N_PAYLOAD = len(PAYLOAD_STATES)
_VX, _AX, _AY = (INPUTS.index(name) for name in ("vx", "ax", "ay"))


def _settings(tuning: ca.SX):
    """The payload part of the tuning vector, by entry name (:data:`PAYLOAD` layout)."""
    return {name: PAYLOAD.value(tuning, name) for name in PAYLOAD.names()}


def prior(tuning: ca.SX) -> ca.SX:
    """Prior covariance :math:`\\mathrm{diag}(\\sigma_m^2, \\sigma_m^2 \\sigma_{x,y,z}^2)`."""
    s = _settings(tuning)
    mass_var = s["payload_mass_std"] ** 2
    return ca.diag(
        ca.vertcat(
            mass_var,
            *[mass_var * s[f"payload_position_std_{axis}"] ** 2 for axis in "xyz"],
        )
    )


def predict(theta, P, started, u, valid, dt, tuning):
    """Random walk over ``dt``; the prior on the first sample (``started`` = 0)."""
    s = _settings(tuning)
    P0 = prior(tuning)
    P = ca.if_else(started, P, P0)
    standing = valid[_VX] * (ca.fabs(u[_VX]) < s["payload_standstill_speed"])
    density = ca.if_else(standing, s["payload_standstill_density"], s["payload_drift_density"])
    scale = ca.vertcat(1, *[s[f"payload_position_std_{axis}"] ** 2 for axis in "xyz"])
    # Never wider than the prior (a long stop leaves the moment it cannot see bounded): the
    # growth of each variance stops at the prior's, which keeps P positive semi-definite.
    growth = ca.fmax(ca.fmin(density * scale * dt, ca.diag(P0) - ca.diag(P)), 0)
    P = P + ca.diag(growth)
    return theta, symmetrise(P)


@dataclasses.dataclass(frozen=True)
class Update:
    """The payload update: parameters, covariance, rows used."""

    theta: ca.SX
    P: ca.SX
    used: ca.SX  # (3,) rows used


def applied(theta, tuning):
    r"""The payload the loads take: each of mass, :math:`S_x`, :math:`S_y` weighted by its
    evidence, :math:`\vartheta_k^3 / (\vartheta_k^2 + a_k^2)` with :math:`a_k` the payload
    the sensors' own errors make appear (``payload_apparent_mass``, ``_moment``): the
    posterior mean when the residual is either a sensor error of that size or a payload
    (a real one, far above it, is taken whole; the height is taken as estimated)."""
    s = _settings(tuning)
    scale = (s["payload_apparent_mass"], s["payload_apparent_moment"], s["payload_apparent_moment"])
    weighted = [theta[k] * theta[k] ** 2 / (theta[k] ** 2 + scale[k] ** 2) for k in range(3)]
    return ca.vertcat(*weighted, theta[3])


def update(theta, P, z, u, gates, p, mask, dt_nominal, tuning, residual: ca.Function) -> Update:
    """Extended Kalman update on the equilibrium rows at the pseudo-measured loads ``z``.

    ``mask`` (3): rows whose suspension and equilibrium inputs are all there.
    """
    s = _settings(tuning)
    r0, J = residual(theta, z, u, gates, p)
    # The mass is weighed by the vertical row alone: the moment rows see it only through
    # m h a in a turn or under braking, where their own mismatch is largest, so they
    # update the first moments (column 0 of their Jacobian left out of the gain).
    J = ca.vertcat(J[0, :], ca.horzcat(ca.DM.zeros(2, 1), J[1:3, 1:]))
    # r(theta) ~ r0 + J (theta' - theta) = 0: the measurement J theta' = J theta - r0.
    target = ca.mtimes(J, theta) - r0
    # The model's mismatch grows with the load transfer it must explain, and it is
    # coloured: a payload's moment g S is the same at every acceleration, so a steady turn
    # teaches S_y little (and a grade S_x) beyond what the quiet driving taught. Each
    # moment row is weighed by its own load transfer, the vertical row by both.
    excitation = {"vertical": u[_AX] ** 2 + u[_AY] ** 2, "pitch": u[_AX] ** 2, "roll": u[_AY] ** 2}
    r = ca.vertcat(
        *[
            s[f"payload_residual_density_{row}"]
            * (1 + excitation[row] / s[f"payload_acceleration_scale_{row}"] ** 2) ** 2
            / dt_nominal
            for row in ("vertical", "pitch", "roll")
        ]
    )
    gate = s["payload_gate"]
    mask = mask * s["payload_estimate"]
    theta_new, P_new, _, _, used = sequential_update_innovations(
        theta, P, target, J, r, mask, lambda i, y, S: y * y <= gate * S
    )
    # A payload outside the car (or lighter than minus half its mass) is no payload: such an
    # update (a hostile sample the guards let through) is not taken.
    ok = plausible(theta_new, p)
    theta_new = ca.if_else(ok, theta_new, theta)
    P_new = ca.if_else(ok, P_new, P)
    return Update(theta=theta_new, P=P_new, used=used * ok)


def unexplained(theta, P, z, u, gates, p, tuning, residual: ca.Function):
    """:math:`J P J^T` (3 x 3): the covariance of the equilibrium residual that the payload's
    uncertainty leaves (0 when it is not estimated: the file is then taken as the car)."""
    _, J = residual(theta, z, u, gates, p)
    return ca.mtimes([J, P, J.T]) * _settings(tuning)["payload_estimate"]


def plausible(theta, p):
    """1 if the payload ``theta`` is one a car can carry: mass in [-m/2, m], its moments
    within the wheelbase, the track and 1 m of height about the file's CG."""
    unpacked = ModelParameters(**{k: p[i] for i, k in enumerate(ModelParameters.names())})
    m = unpacked.mass
    total = m + theta[0]
    reach = (0.5 * (unpacked.lf + unpacked.lr), 0.5 * unpacked.track_front, 1.0)
    ok = (theta[0] >= -0.5 * m) * (theta[0] <= m)
    for k in range(3):
        ok = ok * (ca.fabs(theta[1 + k]) <= reach[k] * total)
    return ok


def residual_function(equilibrium: ca.Function | None = None) -> ca.Function:
    """``payload_residual(theta, z, u, gates, p) -> (r[3], J[3x4])``: the equilibrium
    at the loads ``z`` on the vehicle loaded with ``theta``, and its Jacobian in ``theta``."""
    equilibrium = equilibrium or equilibrium_function()
    theta = ca.SX.sym("theta", N_PAYLOAD)
    z = ca.SX.sym("z", 4)
    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    p = ca.SX.sym("p", len(ModelParameters.names()))
    A, b = equilibrium(u, gates, loaded_parameters_function()(p, theta))
    r = ca.mtimes(A, z) - b
    return ca.Function(
        "payload_residual",
        [theta, z, u, gates, p],
        [r, ca.jacobian(r, theta)],
        ["theta", "z", "u", "gates", "p"],
        ["r", "J"],
    )


def estimated(tuning) -> ca.SX:
    """1 for each of ``MASS_PROPERTIES`` the filter estimates: all with ``payload_estimate``
    but the height, which needs ``payload_position_std_z`` > 0 too (else it is assumed)."""
    s = _settings(tuning)
    on = s["payload_estimate"]
    return ca.vertcat(on, on, on, on * (s["payload_position_std_z"] > 0))


def reported(theta, P, p, tuning):
    """Mass properties of the loaded car (``MASS_PROPERTIES``) and their std (delta method);
    the std of one not :func:`estimated` is 0 (an assumed value, not a certain one)."""
    theta_sym = ca.SX.sym("theta", N_PAYLOAD)
    p_sym, p_unpacked = ModelParameters.symbolic()
    values = mass_properties(p_unpacked, theta_sym)
    f = ca.Function("payload_mass_properties", [theta_sym, p_sym],
                    [values, ca.jacobian(values, theta_sym)])  # fmt: skip
    value, J = f(theta, p)
    variance = ca.diag(ca.mtimes([J, P, J.T]))
    return value, ca.sqrt(ca.fmax(variance, 0)) * estimated(tuning)
