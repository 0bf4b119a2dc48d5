r"""Suspension pseudo-measurement of the wheel loads (Siegloff & Choi §II-B, eq. 3-9).

.. math:: F_{z,i} = F_{z,i,0} + k_a d_i + F^{dam}_a(v_i) + F^{arb}_i
    + g_s F^{stop}_i + g_g F^{link}_i + g_u m_{u,a} (a_{hub,i} - g)

Signs in ISO 8855 with compression ``d > 0`` and ``v = dd/dt > 0`` in bump:
the spring and the damper push the wheel down harder when compressed, and the
anti-roll bar adds load to the more compressed wheel of an axle. (The paper's
eq. 6 prints the opposite sign; a stabiliser bar twisted by a left-side bump
pushes the left wheel down and lifts the right, so ``F_L = +k_arb eta``.)

Terms beyond the paper, each times its gate (``wheelload.models.terms``):

- stops: :func:`~wheelload.models.suspension.elements.stop_force` per axle;
- geometric (link) load transfer, quasi-static, driven by the specific force
  :math:`\tilde f` at the CG (road axes when ``road_frame`` is on): the
  lateral tyre force of an axle :math:`F_{y,f} = m \tilde f_y l_r / l`
  reaches the body at the roll centre, so :math:`\mp F_{y,a} h_{rc,a} / T_a`
  goes to the left/right tyre through the links (corner-based paper eq. 18,
  the :math:`h_{RC}` part); of the rigid longitudinal transfer
  :math:`\mp h F_x / l` per axle (:math:`F_x = m \tilde f_x + D`) the links
  carry the anti-pitch share :math:`\epsilon_a` (brake share when
  :math:`F_x < 0`, drive share otherwise);
- tyre in-plane forces per wheel (same gate, :func:`tyre_force_loads`): each
  wheel's lateral force :math:`F_{y,i}` reaches the body along the line from
  its contact patch through the roll centre, :math:`\mp F_{y,i} h_{rc,a} /
  (T_a/2)`, whose part beyond the axle couple above is the jacking force
  :math:`(F_{y,R} - F_{y,L}) h_{rc,a} / T_a` on both wheels; and the
  suspension carries body-z force while the wheel load is along the road
  normal, so with the body rolled by :math:`\varphi` and pitched by
  :math:`\theta` relative to the road the wheel load exceeds the body-z force
  by :math:`F_{y,i} \sin\varphi - F_{x,i} \sin\theta`. The tyres share
  the axle's lateral and the car's longitudinal force in proportion to the
  rigid-body wheel loads of
  :func:`~wheelload.models.rigid_loads.algebraic_loads` with the roll
  split :math:`\lambda` of :mod:`~wheelload.models.roll_split` (equal friction
  use; mass, geometry and :math:`\lambda` only, so the model stays linear in the suspension
  parameters that identification fits);
- assumption of the ``geometric_transfer`` term: the wheel moves along the body z axis
  (the spring and damper carry the body-z part of the tyre force, the links the rest)
  and the links act at the file's roll-centre heights and anti-pitch shares, as the
  plant's kinematics do (:mod:`wheelload.models.plant.dynamics`). A vehicle without
  link geometry (roll centres 0, anti-pitch 0 in the file) keeps only the body-tilt
  part; on the plant built so, the term lowers method D's pooled RMSE (MTi-1 grade,
  100 Hz: lane change 35.5 -> 27.4 N, brake in a turn 20.2 -> 18.0 N) while the KF's
  moves by +0.5 % and +10 % (21.5 -> 21.6 N, 23.4 -> 25.7 N). A file whose geometry the
  car lacks adds its link loads as an error: the bundled sports car's file on that
  plant gives D 85 N on the brake in a turn (20 N without the term), 160 N on each front
  wheel while braking. The term cannot see the geometry: the file must state it;
- unsprung inertia: a hub accelerometer (specific force along body z,
  :math:`+g` at rest) gives the unsprung mass's load :math:`m_u a_{hub}`;
  its static part is already in :math:`F_{z,i,0}`.

Example
-------
>>> f = suspension_function()
>>> z = f(u, gates, ModelParameters.from_vehicle(vehicle).vector())
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.aero import aero_forces
from wheelload.models.body_attitude import attitude_from_travel
from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.models.inputs import INPUTS, ModelInputs
from wheelload.models.parameters import ModelParameters
from wheelload.models.rigid_loads import algebraic_loads
from wheelload.models.suspension.elements import (
    anti_roll_bar_forces,
    damper_force,
    piecewise_damper_force,
    stop_force,
)
from wheelload.models.suspension.parts import link_loads, travel_loads
from wheelload.models.terms import GATES, gate, road_motion, small_sin

__all__ = [
    "anti_roll_bar_forces",
    "damper_force",
    "geometric_loads",
    "piecewise_damper_force",
    "stop_force",
    "suspension_function",
    "travel_function",
    "travel_loads",
    "tyre_force_loads",
]


def tyre_force_loads(f_road, vx, d, p: ModelParameters) -> list:
    r"""Jacking and body-tilt load per corner FL, FR, RL, RR [N] (module docstring).

    .. math::
        F_{y,i} = F_{y,a} \frac{F_{z,i}}{F_{z,L} + F_{z,R}}, \quad
        F_{x,i} = F_x \frac{F_{z,i}}{\sum_j F_{z,j}}, \quad
        \Delta F_{z,i} = \frac{(F_{y,R} - F_{y,L}) h_{rc,a}}{T_a}
            + F_{y,i} \sin\varphi - F_{x,i} \sin\theta

    with :math:`F_{y,f} = m \tilde f_y l_r / l`, :math:`F_x = m \tilde f_x + D`,
    :math:`F_{z,i}` the rigid-body loads of
    :func:`~wheelload.models.rigid_loads.algebraic_loads` at :math:`\tilde f`
    with the front share ``p.roll_split_front`` of the lateral transfer (clipped at
    0) and :math:`\varphi, \theta` the body attitude relative to the road
    (ISO 8855: right side down, nose down) of
    :func:`~wheelload.models.body_attitude.attitude_from_travel` on the corner
    motions :math:`d_i + (F_{z,i} - F_{z,i}^{rest}) / k_{t,a}` (travel plus
    tyre deflection under the rigid-body loads, so that the attitude, too,
    holds no identified parameter).
    """
    wheelbase = p.lf + p.lr
    _, drag = aero_forces(vx, p)
    force_x = p.mass * f_road[0] + drag
    rigid = algebraic_loads(f_road, p, p.roll_split_front)
    rest = algebraic_loads(ca.vertcat(0.0, 0.0, GRAVITY), p, p.roll_split_front)
    rates = (p.tyre_rate_front, p.tyre_rate_front, p.tyre_rate_rear, p.tyre_rate_rear)
    motion = [d[i] + (rigid[i] - rest[i]) / rates[i] for i in range(4)]
    phi, theta = attitude_from_travel(motion, p.track_front, p.track_rear, wheelbase)
    loads = [ca.fmax(rigid[i], 0.0) for i in range(4)]
    total = ca.fmax(loads[0] + loads[1] + loads[2] + loads[3], 1.0)
    axles = ((p.lr, p.roll_centre_front, p.track_front), (p.lf, p.roll_centre_rear, p.track_rear))
    result = []
    for axle, (arm, height, track) in enumerate(axles):
        left, right = loads[2 * axle], loads[2 * axle + 1]
        force_y = p.mass * f_road[1] * arm / wheelbase
        share_left = left / ca.fmax(left + right, 1.0)
        share_right = right / ca.fmax(left + right, 1.0)
        jacking = force_y * (share_right - share_left) * height / track
        for share, load in ((share_left, left), (share_right, right)):
            tilt = force_y * share * small_sin(phi) - force_x * load / total * small_sin(theta)
            result.append(jacking + tilt)
    return result


def geometric_loads(f_road, vx, d, p: ModelParameters) -> list:
    """Load per corner FL, FR, RL, RR of the ``geometric_transfer`` term [N] (ungated).

    :func:`~wheelload.models.suspension.parts.link_loads` (roll-centre and anti-pitch
    couples) plus :func:`tyre_force_loads` (jacking and body tilt).
    """
    couples = link_loads(f_road, vx, p)
    tyres = tyre_force_loads(f_road, vx, d, p)
    return [couple + tyre for couple, tyre in zip(couples, tyres, strict=True)]


def suspension_loads(u, gates, p: ModelParameters, damper=None) -> ca.SX:
    """Pseudo-measured wheel loads FL, FR, RL, RR from the inputs ``u`` (eq. 9 + terms).

    :func:`travel_loads` (``damper`` as there) plus each gated term.
    """
    inputs = ModelInputs.unpack(u)
    d = inputs.d
    f_road = road_motion(inputs, gates, p)[0]
    paper = travel_loads(d, inputs.v, p, damper)
    links = geometric_loads(f_road, inputs.vx, d, p)
    axles = p.axles("bump_gap", "rebound_gap", "stop_rate", "stop_progressive", "unsprung")
    loads = []
    for axle, (bump, rebound, k1, k2, unsprung) in enumerate(axles):
        for wheel in (2 * axle, 2 * axle + 1):
            load = paper[wheel]
            load += gate(gates, "stops") * stop_force(d[wheel], bump, rebound, k1, k2)
            load += gate(gates, "geometric_transfer") * links[wheel]
            hub = inputs.hub[wheel] - GRAVITY
            load += gate(gates, f"unsprung_{WHEELS[wheel]}") * unsprung * hub
            loads.append(load)
    return ca.vertcat(*loads)


def suspension_function(name: str = "suspension_load") -> ca.Function:
    """``name(u, gates, p) -> z[4]``: the suspension pseudo-measurement as a CasADi Function."""
    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(
        name, [u, gates, p_vector], [suspension_loads(u, gates, p)], ["u", "gates", "p"], ["z"]
    )


def travel_function(name: str = "suspension_travel_load") -> ca.Function:
    """``name(d[4], v[4], p) -> z[4]``: the paper's pseudo-measurement (eq. 9), no terms."""
    d = ca.SX.sym("d", 4)
    v = ca.SX.sym("v", 4)
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(name, [d, v, p_vector], [travel_loads(d, v, p)], ["d", "v", "p"], ["z"])


def piecewise_damper_names(knots) -> tuple[str, ...]:
    """Entry names of the piecewise damper's slope vector: ``damper_{push,pull}_{axle}_{j}``."""
    return tuple(
        f"damper_{side}_{axle}_{j}"
        for axle in ("front", "rear")
        for side in ("push", "pull")
        for j in range(len(knots) + 1)
    )


def piecewise_damper_suspension_function(
    knots, name: str = "suspension_load_piecewise_damper"
) -> ca.Function:
    """``name(u, gates, p, damper) -> z[4]``: :func:`suspension_function` with the damper map.

    ``damper`` holds the slopes in :func:`piecewise_damper_names` order; the
    linear push/pull entries of ``p`` are not used.
    """
    knots = tuple(float(k) for k in knots)
    if not knots or any(k <= 0 for k in knots) or list(knots) != sorted(set(knots)):
        raise ValueError(f"damper knots must be increasing and > 0 m/s, got {knots}")
    segments = len(knots) + 1
    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    slopes = ca.SX.sym("damper", 4 * segments)
    p_vector, p = ModelParameters.symbolic()

    def damper(speed, axle):
        base = 2 * segments * axle
        push = [slopes[base + j] for j in range(segments)]
        pull = [slopes[base + segments + j] for j in range(segments)]
        return piecewise_damper_force(speed, knots, push, pull)

    z = suspension_loads(u, gates, p, damper)
    return ca.Function(
        name, [u, gates, p_vector, slopes], [z], ["u", "gates", "p", "damper"], ["z"]
    )
