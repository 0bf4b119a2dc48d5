r"""Model terms beyond the paper: gates, IMU lever arm and mounting, road-frame attitude.

Each term is switched by the vehicle file's ``[model]`` section (a 0/1
parameter, so the generated C keeps the switch at run time) and, where it
needs an optional input, gated per sample by that input's validity. The
gate vector :data:`GATES` is the single place where both meet; the
suspension and equilibrium models multiply each term by its gate.

Terms (what each adds, and where):

- ``road_frame`` (equilibrium): body roll :math:`\phi` and pitch
  :math:`\theta` relative to the road from the four travel sensors (Wang et
  al. road-angle paper eq. 7, with the tyre deflection added) or, where a
  travel is missing (gate ``equilibrium_attitude``), from the quasi-static
  equilibrium of the suspension under the measured specific force
  (:func:`~wheelload.models.body_attitude.attitude_from_equilibrium`), the specific
  force rotated into the road frame (Kiani et al. corner-based paper, the
  :math:`\tilde a` terms of eq. 17-18) and the CG moved by roll, pitch and
  heave in the moment rows (:func:`wheelload.models.equilibrium`).
- ``body_inertia`` (equilibrium): :math:`I_{xx}\dot p`, :math:`I_{yy}\dot q`.
- ``geometric_transfer`` (suspension): load through the links at the
  roll-centre height and anti-pitch geometry.
- ``stops`` (suspension): bump and rebound stops.
- ``unsprung_inertia`` (suspension, vertical row): :math:`m_u (a_{hub} - g)`.
- ``imu_lever_arm``: specific force moved from the IMU to the sprung CG.

The IMU mounting orientation (``imu_orientation``) is applied whenever an
angle is non-zero (gate ``imu_mounting``, no switch).

The parity model (:func:`parity_model`) switches every term on: the vehicle's complete
physics, against which the fault monitor checks the sensors and the file check
(:mod:`wheelload.estimators.logs.model_error`) the vehicle file.
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.body_attitude import (
    attitude_from_equilibrium,
    attitude_from_travel,
    attitude_travel,
    road_frame,
)
from wheelload.models.inputs import (
    BODY_RATE_DERIVATIVES,
    BODY_RATES,
    HUB_ACCELERATION,
    INPUTS,
    SPECIFIC_FORCE,
    SPEED,
    TRAVEL,
    ModelInputs,
    input_index,
)
from wheelload.models.parameters import ModelParameters
from wheelload.models.suspension.elements import anti_roll_bar_forces

#: Order of the gate vector taken by the suspension and equilibrium models.
GATES = (
    "road_frame",
    "equilibrium_attitude",
    "body_inertia",
    "geometric_transfer",
    "stops",
    "unsprung_fl",
    "unsprung_fr",
    "unsprung_rl",
    "unsprung_rr",
    "imu_lever_arm",
    "imu_mounting",
)
#: Terms that can be dropped for a missing input, in the order of the ``dropped``
#: output (StepFlag bits 16-19): body inertia (no rate derivatives); unsprung
#: inertia (a hub accelerometer); road frame or link loads (an accelerometer
#: axis or the speed; a missing travel sensor keeps the road frame on, with its
#: attitude from the equilibrium, and sets the same flag); IMU lever arm or
#: mounting (no rates, or an accelerometer axis of a tilted IMU).
DROPPABLE = ("body_inertia", "unsprung_inertia", "road_frame_or_links", "imu_lever_arm_or_mounting")


def _all_valid(valid, names) -> ca.SX:
    gate = 1
    for i in input_index(names):
        gate = gate * valid[i]
    return gate


def term_gates(valid, p: ModelParameters) -> tuple[ca.SX, ca.SX]:
    """Gates (switch times input validity, :data:`GATES` order) and dropped terms.

    ``dropped[k]`` is 1 where term :data:`DROPPABLE` ``[k]`` is switched on
    but an input it needs is missing in this sample. The ``road_frame`` term
    needs the accelerometer; without a travel sensor (gate
    ``equilibrium_attitude``) it takes the attitude from the equilibrium and
    is flagged in ``dropped`` as if dropped.
    """
    rates_ok = _all_valid(valid, BODY_RATES + BODY_RATE_DERIVATIVES)
    inertia_ok = _all_valid(valid, BODY_RATE_DERIVATIVES[:2])
    acc_ok = _all_valid(valid, SPECIFIC_FORCE)
    travel_ok = _all_valid(valid, TRAVEL) * acc_ok
    links_ok = acc_ok * _all_valid(valid, SPEED)
    hub_ok = [_all_valid(valid, (name,)) for name in HUB_ACCELERATION]
    R = p.imu_rotation()
    mounted = 0
    for i in range(3):
        for j in range(3):
            mounted = ca.logic_or(mounted, R[i, j] != (1.0 if i == j else 0.0))
    gates = ca.vertcat(
        p.term_road_frame * acc_ok,
        1 - travel_ok,
        p.term_body_inertia * inertia_ok,
        p.term_geometric_transfer * links_ok,
        p.term_stops,
        *[p.term_unsprung_inertia * ok for ok in hub_ok],
        p.term_imu_lever_arm * rates_ok,
        mounted * acc_ok,
    )
    hub_all = hub_ok[0] * hub_ok[1] * hub_ok[2] * hub_ok[3]
    road_or_links = ca.fmax(p.term_road_frame * (1 - travel_ok),
                            p.term_geometric_transfer * (1 - links_ok))  # fmt: skip
    imu = ca.fmax(p.term_imu_lever_arm * (1 - rates_ok), mounted * (1 - acc_ok))
    dropped = ca.vertcat(
        p.term_body_inertia * (1 - inertia_ok),
        p.term_unsprung_inertia * (1 - hub_all),
        road_or_links,
        imu,
    )
    return gates, dropped


def gates_function(name: str = "model_gates") -> ca.Function:
    """``name(u_valid, p) -> (gates, dropped)`` (see :func:`term_gates`)."""
    valid = ca.SX.sym("u_valid", len(INPUTS))
    p_vector, p = ModelParameters.symbolic()
    gates, dropped = term_gates(valid, p)
    return ca.Function(name, [valid, p_vector], [gates, dropped], ["u_valid", "p"],
                       ["gates", "dropped"])  # fmt: skip


def gate(gates, name: str):
    """The gate of term ``name``."""
    return gates[GATES.index(name)]


def rotation_x(angle) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))


def rotation_y(angle) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


def rotation_z(angle) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def mounting_rotation(p: ModelParameters, on=1) -> ca.SX:
    r"""Sensor-to-body rotation :math:`R_z(\psi_m) R_y(\theta_m) R_x(\phi_m)` (from ``p``).

    A vector measured in the sensor axes is :math:`R v` in the body axes. With
    ``on`` = 0 (a level IMU, or a missing accelerometer axis) the identity, so
    that a level IMU's axes do not mix and a missing axis skips only its rows.
    """
    eye = ca.DM.eye(3)
    return eye + on * (p.imu_rotation() - eye)


def small_sin(angle):
    r""":math:`\sin a \approx a - a^3/6` (error below 1e-7 for :math:`|a| < 0.1` rad)."""
    return angle * (1 - angle * angle / 6)


def small_cos(angle):
    r""":math:`\cos a \approx 1 - a^2/2 + a^4/24` (error below 1e-8 for :math:`|a| < 0.1`)."""
    square = angle * angle
    return 1 - square / 2 + square * square / 24


def body_motion(inputs: ModelInputs, gates, p: ModelParameters):
    r"""Specific force at the sprung CG, body rates and their derivative, body axes.

    .. math:: f_{CG} = R f_{IMU} - \dot\omega \times r - \omega \times (\omega \times r),
        \quad \omega = R \omega_{IMU}, \quad \dot\omega = R \dot\omega_{IMU}

    with :math:`R` the mounting rotation and :math:`r` the IMU position
    relative to the sprung CG; the lever-arm part carries its gate.
    """
    R = mounting_rotation(p, gate(gates, "imu_mounting"))
    f = R @ inputs.acc
    omega = R @ inputs.rates
    omega_dot = R @ inputs.rate_dots
    r = ca.vertcat(p.imu_x, p.imu_y, p.imu_z)
    arm = ca.cross(omega_dot, r) + ca.cross(omega, ca.cross(omega, r))
    return f - gate(gates, "imu_lever_arm") * arm, omega, omega_dot


def corner_deflection(d, p: ModelParameters) -> list:
    r"""Vertical motion of each corner relative to the road: travel plus tyre deflection.

    .. math:: e_i = d_i + (k_a d_i + F^{arb}_i) / k_{t,a}

    (the spring and bar load change also compresses the tyre; the damper is
    left out: it is quasi-static).
    """
    result = []
    axles = p.axles("spring", "arb_rate", "arb_ratio", "tyre_rate")
    for axle, (spring, arb_rate, arb_ratio, tyre_rate) in enumerate(axles):
        left, right = 2 * axle, 2 * axle + 1
        arb = anti_roll_bar_forces(d[left], d[right], arb_rate, arb_ratio)
        for side, wheel in enumerate((left, right)):
            result.append(d[wheel] + (spring * d[wheel] + arb[side]) / tyre_rate)
    return result


def attitude_from_deflection(d, p: ModelParameters):
    r"""Body roll, pitch (rad) and CG heave compression (m) relative to the road plane.

    Small angles (road-angle paper eq. 7,
    :func:`~wheelload.models.body_attitude.attitude_from_travel`, on the
    corner deflections :math:`e` of :func:`corner_deflection`, travel plus tyre):

    .. math::
        \phi = \tfrac12\left(\frac{e_{FR} - e_{FL}}{T_f} + \frac{e_{RR} - e_{RL}}{T_r}\right),
        \quad \theta = \frac{\bar e_f - \bar e_r}{l_f + l_r},
        \quad e_{CG} = \frac{l_r \bar e_f + l_f \bar e_r}{l_f + l_r}

    ISO 8855 signs: :math:`\phi > 0` right side down (the body rolls to the
    right in a left turn), :math:`\theta > 0` nose down (braking). Relative
    to the static attitude (the IMU is taken as level at rest).
    """
    e = corner_deflection(d, p)
    wheelbase = p.lf + p.lr
    phi, theta = attitude_from_travel(e, p.track_front, p.track_rear, wheelbase)
    front, rear = 0.5 * (e[0] + e[1]), 0.5 * (e[2] + e[3])
    heave = (p.lr * front + p.lf * rear) / wheelbase
    return phi, theta, heave


def road_motion(inputs: ModelInputs, gates, p: ModelParameters):
    r"""Specific force at the CG in road axes, body rates and derivatives, attitude.

    .. math:: \tilde f = R_y(\theta) R_x(\phi) f_{CG}

    (the corner-based paper's :math:`\tilde a` terms,
    :func:`~wheelload.models.body_attitude.road_frame`; sine and cosine by
    their Taylor polynomials, :func:`small_sin`, :func:`small_cos`: body
    angles stay below 0.1 rad, and a step evaluates no trigonometric function);
    with the ``road_frame`` gate off, :math:`\phi = \theta = e_{CG} = 0`.
    The attitude comes from the travels, or with the ``equilibrium_attitude``
    gate on (a travel missing) from the travels of the quasi-static roll and
    pitch (:func:`~wheelload.models.body_attitude.attitude_from_equilibrium`),
    tyre deflection added either way.
    Returns ``(f_road, omega, omega_dot, phi, theta, heave)``.
    """
    f, omega, omega_dot = body_motion(inputs, gates, p)
    on = gate(gates, "road_frame")
    quasi_static = attitude_travel(*attitude_from_equilibrium(f, p), p)
    travel = ca.if_else(gate(gates, "equilibrium_attitude"), quasi_static, inputs.d)
    phi, theta, heave = (on * value for value in attitude_from_deflection(travel, p))
    f_road = road_frame(f, phi, theta, sine=small_sin, cosine=small_cos)
    return f_road, omega, omega_dot, phi, theta, heave


#: The [model] switches in the parameter vector: on for the parity model (sensor and file
#: checks).
_TERM_SWITCHES = [k for k, name in enumerate(ModelParameters.names()) if name.startswith("term_")]


def parity_model(suspension: ca.Function, equilibrium: ca.Function, u, valid, p):
    r"""``(z, A, b, signatures)`` of the parity test, with every model term switched on.

    The monitor checks the travels and the IMU against the vehicle's complete physics
    (each term whose inputs are valid in the sample), whatever the vehicle file's
    ``[model]`` switches choose for the estimator's updates: a model without the link
    or road-frame terms (the paper's) leaves a parity residual of several hundred N
    on a clean lap, which the signatures of the travel faults explain. ``u``: the
    sanitised inputs, ``valid`` their validity, ``p`` the parameter vector.

    Signatures in the parity space from the models' Jacobians: a travel fault moves
    :math:`b - A z` by :math:`-A\,\partial z / \partial d`, an accelerometer fault by
    :math:`\partial b / \partial a`.
    """
    p = ca.vertcat(*[1 if k in _TERM_SWITCHES else p[k] for k in range(p.shape[0])])
    gates, _ = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    travel, acc = input_index(TRAVEL), input_index(SPECIFIC_FORCE)
    d_sym, acc_sym = ca.SX.sym("d", 4), ca.SX.sym("acc", 3)
    u_d = with_entries(u, travel, d_sym)
    u_acc = with_entries(u, acc, acc_sym)
    d_now = ca.vertcat(*[u[k] for k in travel])
    acc_now = ca.vertcat(*[u[k] for k in acc])
    Jd = ca.substitute(ca.jacobian(suspension(u_d, gates, p), d_sym), d_sym, d_now)
    B = ca.substitute(ca.jacobian(equilibrium(u_acc, gates, p)[1], acc_sym), acc_sym, acc_now)
    return z, A, b, ca.horzcat(-ca.mtimes(A, Jd), B)


def with_entries(u: ca.SX, index: list[int], values: ca.SX) -> ca.SX:
    """``u`` with the entries at ``index`` replaced by ``values``."""
    entries = [u[k] for k in range(u.shape[0])]
    for j, k in enumerate(index):
        entries[k] = values[j]
    return ca.vertcat(*entries)
