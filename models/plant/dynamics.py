r"""Full-vehicle ground-truth plant: 6-DOF body, four unsprung masses, four wheel spins.

State (32): path position ``s, n`` and CG height ``z``; Euler roll, pitch and
heading relative to the centre line ``phi, theta, psi``; body velocities
``u, v, w`` and rates ``p, q, r`` (ISO 8855 body axes at the sprung CG);
suspension compression ``d`` and rate ``dd`` per corner (d > 0 in bump, 0 at
static equilibrium on level ground); wheel spin ``omega``; transient slip
``kappa`` and ``tan(alpha)`` per tyre (first-order relaxation, Pacejka ch. 7).
Input (9): front road-wheel steer angle, four drive torques, four brake
torques (brakes oppose the spin).

Equations (body frame, sprung CG; corner i with wheel centre :math:`r_{W,i}`
and contact point :math:`r_{P,i}`):

.. math::
    m (\dot u + q w - r v,\ \dot v + r u - p w) &= \textstyle\sum F_{t,i} + F_a + m g_b
        \quad \text{(x, y; whole-vehicle mass)} \\
    m_s (\dot w + p v - q u) &= \textstyle\sum F_{s,i} + L + m_s g_{b,z} \\
    I \dot\omega + \omega \times I \omega &= \textstyle\sum r_{W,i} \times C_i
        + (r_{P,i} - r_{W,i}) \times F_{t,i} + r_a \times F_a \\
    m_{u,i} (a_z + [\dot\omega \times r_{W,i} + \omega \times \omega \times r_{W,i}]_z
        + \ddot d_i) &= F_{t,i,z} + m_{u,i} g_{b,z} - F_{s,i}

where :math:`C_i = (F_{t,i,x} + m_{u,i}(g_{b,x} - a_x),\ F_{t,i,y} +
m_{u,i}(g_{b,y} - a_y),\ F_{s,i} + J_i)` is the force a corner passes to the body
(the suspension links carry the in-plane part, the spring, damper, bar and
stops the vertical part :math:`F_{s,i}`; the unsprung masses move in-plane with
the body CG). The links also carry a vertical (jacking) force

.. math:: J_i = -F_{y,i} h_{rc,a} / y_i \mp F_{x,i} \tan\beta_{a}

so that a tyre's lateral force reaches the body along the line through the
axle's roll centre (height :math:`h_{rc,a}` above ground on the centre line)
and its longitudinal force along the side-view anti-pitch line
(:math:`-` front, :math:`+` rear); :math:`\tan\beta_a = \epsilon_a h / (l\,
s_a)` with the vehicle file's anti-pitch share :math:`\epsilon_a` and the
axle's brake or drive share :math:`s_a` (0 where the share is 0), so that the
links carry :math:`\epsilon_a` of the axle's rigid load transfer as the
estimators' model assumes (``wheelload.models.suspension.pseudo_measurement``). The unsprung
equation carries :math:`-J_i` with :math:`F_{s,i}`.
The tyre force :math:`F_{t,i} = F_x e_x + F_y e_y + F_z n` acts along the
local road normal and in the road plane; :math:`F_z = k_t \max(0, r_0 -
\text{distance from wheel centre to road plane})`, so a tyre can leave the
ground. Integration: classical RK4 with a fixed step, compiled.

A plant built with ``payload`` (:func:`plant_dynamics`) takes a point mass on the
sprung body as four more inputs; its body equations are
:func:`loaded_body_accelerations` (Newton-Euler about the file's sprung CG), the file's
springs and preloads unchanged, so that travel stays measured from the file's
reference state.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from wheelload.models.conventions import GRAVITY, WHEELS
from wheelload.models.family.tyre_forces import SPIN_SMOOTHING, spin_direction
from wheelload.models.mass_properties import static_loads, vehicle_mass_centre
from wheelload.models.payload import inertia_about, sprung_body, with_point_mass
from wheelload.models.plant.road_surface import RoadSurface, road_lookup
from wheelload.models.plant.tyre import tyre_forces
from wheelload.models.runtime.build_folder import cached_function
from wheelload.models.suspension.elements import anti_roll_bar_forces, stop_force
from wheelload.models.terms import rotation_x, rotation_y, rotation_z
from wheelload.models.vehicle.description import Vehicle
from wheelload.models.vehicle.plant_section import DamperMap, Plant
from wheelload.models.vehicle.wheel_geometry import loaded_radii, rolling_radius, wheel_centres

STATE_NAMES = (
    ("s", "n", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r")
    + tuple(f"d_{w}" for w in WHEELS)
    + tuple(f"dd_{w}" for w in WHEELS)
    + tuple(f"omega_{w}" for w in WHEELS)
    + tuple(f"kappa_{w}" for w in WHEELS)
    + tuple(f"alpha_{w}" for w in WHEELS)
)
INPUT_NAMES = ("steer",) + tuple(f"drive_{w}" for w in WHEELS) + tuple(f"brake_{w}" for w in WHEELS)
# Inputs of a plant built to carry a payload, after INPUT_NAMES (models/payload.py).
PAYLOAD_INPUT_NAMES = ("payload_mass", "payload_x", "payload_y", "payload_z")
# Outputs of one chunk, sampled at its last step.
OUTPUT_NAMES = (
    tuple(f"fz_{w}" for w in WHEELS)
    + ("ax", "ay", "az")  # specific force at the IMU, body axes
    + ("ax_cg", "ay_cg", "az_cg")  # kinematic acceleration of the sprung CG, body axes
    + tuple(f"az_{w}" for w in WHEELS)  # hub specific force, body z
    + ("wx", "wy", "wz")  # body rates in the IMU's sensor axes
)
STATE = {name: i for i, name in enumerate(STATE_NAMES)}
OUTPUT = {name: i for i, name in enumerate(OUTPUT_NAMES)}


class PlantError(ValueError):
    """A vehicle or setting the plant cannot be built from."""


@dataclass(frozen=True, kw_only=True)
class Corner:
    """Numbers of one corner, derived from the vehicle file."""

    x: float  # m, wheel centre ahead of the sprung CG
    y: float  # m, to the left
    z_static: float  # m, wheel centre relative to the sprung CG at static equilibrium
    radius: float  # m, unloaded tyre radius
    tyre_rate: float  # N/m
    unsprung: float  # kg
    preload: float  # N, spring force at d = 0
    static_load: float  # N
    spring: float  # N/m
    damper: DamperMap
    bump_gap: float  # m
    rebound_gap: float  # m
    stop_rate: float  # N/m
    stop_progressive_rate: float  # N/m^2
    roll_centre: float  # m, above ground
    anti_brake: float  # -, tan(beta) of the side-view line when braking (F_x < 0)
    anti_drive: float  # -, tan(beta) when driving (F_x > 0)
    spin_inertia: float  # kg m^2
    nominal_load: float  # N, tyre F_z0
    left: bool


def vehicle_plant(vehicle: Vehicle) -> Plant:
    """The vehicle's ``[plant]`` section, or an error naming the file key."""
    if vehicle.plant is None:
        raise PlantError(f"vehicle '{vehicle.name}' has no [plant] section")
    return vehicle.plant


def corners(vehicle: Vehicle) -> tuple[Corner, ...]:
    """Corner data FL, FR, RL, RR; the preloads hold the static loads of static_loads()."""
    plant = vehicle_plant(vehicle)
    g, t, m, susp = vehicle.geometry, vehicle.tyres, vehicle.mass, vehicle.suspension
    loads = static_loads(vehicle)
    centres = wheel_centres(g)
    loaded = loaded_radii(t, loads)
    centre = vehicle_mass_centre(vehicle)
    rise = centre.height / (centre.lf + centre.lr)  # rigid transfer per unit F_x
    drive = plant.driveline

    def tan_beta(share_of_transfer: float, force_share: float) -> float:
        return share_of_transfer * rise / force_share if force_share > 0 else 0.0

    result = []
    for i in range(4):
        front = i < 2
        axle = susp.front if front else susp.rear
        brake_share = drive.brake_share_front if front else 1.0 - drive.brake_share_front
        drive_share = drive.drive_share_front if front else 1.0 - drive.drive_share_front
        left = i % 2 == 0
        radius = t.radius_front if front else t.radius_rear
        rate = t.vertical_stiffness_front if front else t.vertical_stiffness_rear
        unsprung = 0.5 * (m.unsprung_front if front else m.unsprung_rear)
        result.append(
            Corner(
                x=centres[i][0],
                y=centres[i][1],
                z_static=loaded[i] - g.cg_height,
                radius=radius,
                tyre_rate=rate,
                unsprung=unsprung,
                preload=loads[i] - unsprung * GRAVITY,
                static_load=float(loads[i]),
                spring=(susp.front if front else susp.rear).spring_rate,
                damper=plant.dampers.front if front else plant.dampers.rear,
                bump_gap=axle.bump_gap,
                rebound_gap=axle.rebound_gap,
                stop_rate=axle.stop_rate,
                stop_progressive_rate=axle.stop_progressive_rate,
                roll_centre=axle.roll_centre_height,
                anti_brake=tan_beta(axle.anti_pitch_brake, brake_share),
                anti_drive=tan_beta(axle.anti_pitch_drive, drive_share),
                spin_inertia=(
                    plant.wheels.spin_inertia_front if front else plant.wheels.spin_inertia_rear
                ),
                nominal_load=(
                    plant.tyre.nominal_load_front if front else plant.tyre.nominal_load_rear
                ),
                left=left,
            )
        )
    return tuple(result)


def damper_map_force(v, damper: DamperMap):
    r"""Damper force [N] (> 0 resists compression) by linear interpolation of the map.

    Through (0, 0), :math:`(v_1, F_1)`, :math:`(v_2, F_2)`, extended with the
    last slope; rebound (v < 0) uses the pull points with a negative sign.
    """
    (v1, v2) = damper.velocities

    def branch(speed, f1, f2):
        low = f1 / v1 * speed
        high = f1 + (f2 - f1) / (v2 - v1) * (speed - v1)
        return ca.if_else(speed <= v1, low, high)

    push = branch(v, *damper.push)
    pull = -branch(-v, *damper.pull)
    return ca.if_else(v >= 0, push, pull)


def corner_suspension_force(corner: Corner, d, dd, arb):
    r"""Vertical force the suspension of one corner passes to the body [N].

    .. math:: F_s = F_{pre} + k d + F_{dam}(\dot d) + F_{arb} + F_{stop}(d)

    Preload, spring, damper map, the bar's share ``arb`` and the corner's
    stops (not the link force, which does not act through the spring-damper
    unit); also driven on its own by the component rig (``studies/drive/rig.py``).
    """
    return (
        corner.preload
        + corner.spring * d
        + damper_map_force(dd, corner.damper)
        + arb
        + stop_force(
            d, corner.bump_gap, corner.rebound_gap, corner.stop_rate, corner.stop_progressive_rate
        )
    )


def _rotation(phi, theta, psi):
    """Body-to-path rotation :math:`R_z(\\psi) R_y(\\theta) R_x(\\phi)`."""
    cf, sf = ca.cos(phi), ca.sin(phi)
    ct, st = ca.cos(theta), ca.sin(theta)
    cp, sp = ca.cos(psi), ca.sin(psi)
    return ca.vertcat(
        ca.horzcat(cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf),
        ca.horzcat(sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf),
        ca.horzcat(-st, ct * sf, ct * cf),
    )


def _unit(vector):
    return vector / ca.norm_2(vector)


def _skew(r):
    """:math:`[r]_\times`, so that :math:`[r]_\times v = r \times v`."""
    return ca.vertcat(
        ca.horzcat(0, -r[2], r[1]), ca.horzcat(r[2], 0, -r[0]), ca.horzcat(-r[1], r[0], 0)
    )


def loaded_body_accelerations(vehicle: Vehicle, payload, force, moment, unsprung, omega, g_body):
    r"""Acceleration of the file's sprung CG and :math:`\dot\omega` with a payload on the body.

    The sprung body carries the point mass of ``payload = (m_p, r_p)``
    (:func:`~wheelload.models.payload.with_point_mass`: :math:`m'`, centre :math:`c`,
    inertia :math:`I_O` about the file's sprung CG O). Newton-Euler about O:

    .. math::
        M a + m' (\dot\omega \times c + \omega \times \omega \times c) &= F + M g_b \\
        I_O \dot\omega + \omega \times I_O \omega + m' c \times a &= M_O(a) + m' c \times g_b

    with :math:`M = \mathrm{diag}(m' + m_u, m' + m_u, m')` (the unsprung masses move
    in-plane with the body, as without payload), ``force`` F the tyre, aerodynamic and
    suspension forces, and :math:`M_O(a) = M_0 - U a` the moment of the corners with
    ``unsprung`` :math:`U = \sum m_{u,i} [r_{W,i}]_\times \mathrm{diag}(1, 1, 0)` the
    in-plane inertia of the unsprung masses; ``moment`` is :math:`M_0`. Eliminating
    :math:`a` leaves a 3 x 3 system for :math:`\dot\omega`. With :math:`m_p = 0` it is the
    plant's own body equations (module docstring).
    """
    body = with_point_mass(sprung_body(vehicle), payload[0], payload[1:4])
    first = body.mass * body.centre  # m' c
    inertia = inertia_about(body, ca.DM.zeros(3))
    in_plane = vehicle.mass.total - vehicle.mass.sprung + body.mass
    mass = ca.vertcat(in_plane, in_plane, body.mass)
    cross_c = _skew(first)
    f1 = force + mass * g_body - ca.cross(omega, ca.cross(omega, first))
    f2 = moment + ca.cross(first, g_body) - ca.cross(omega, inertia @ omega)
    coupling = cross_c + unsprung
    lhs = inertia + coupling @ ca.diag(1.0 / mass) @ cross_c
    omega_dot = ca.solve(lhs, f2 - coupling @ (f1 / mass))
    acc = (f1 + cross_c @ omega_dot) / mass
    return acc, omega_dot


def wheel_torque(drive, brake, direction):
    r"""Torque on a wheel about its spin axis from drive and brake [N m], > 0 forward.

    .. math:: T = T_{drive} - T_{brake} \tanh(\omega / \omega_s)

    ``direction`` is :func:`spin_direction` of the wheel's spin.
    """
    return drive - brake * direction


def wheel_force_function(vehicle: Vehicle) -> ca.Function:
    r"""``plant_wheel_forces(kappa, alpha, fz, spin, drive, brake) -> (fx, fy, torque)``.

    Per wheel (4 x 1 each, FL FR RL RR) the plant's own tyre forces in the tyre frame
    (:func:`~wheelload.models.plant.tyre.tyre_forces`: ``fx`` along the wheel heading in
    the road plane, ``fy`` to its left, ISO 8855) and the drive/brake torque on the wheel
    (:func:`wheel_torque`), from the transient slips, the normal loads and the applied
    inputs: the reference the tyre-force estimators are scored against.
    """
    plant = vehicle_plant(vehicle)
    kappa, alpha, fz = ca.SX.sym("kappa", 4), ca.SX.sym("alpha", 4), ca.SX.sym("fz", 4)
    spin, drive, brake = ca.SX.sym("spin", 4), ca.SX.sym("drive", 4), ca.SX.sym("brake", 4)
    fx, fy, torque = [], [], []
    for i, c in enumerate(corners(vehicle)):
        f_x, f_y = tyre_forces(kappa[i], alpha[i], fz[i], c.nominal_load, plant.tyre)
        fx.append(f_x)
        fy.append(f_y)
        torque.append(wheel_torque(drive[i], brake[i], spin_direction(spin[i])))
    return ca.Function(
        "plant_wheel_forces",
        [kappa, alpha, fz, spin, drive, brake],
        [ca.vertcat(*fx), ca.vertcat(*fy), ca.vertcat(*torque)],
        ["kappa", "alpha", "fz", "spin", "drive", "brake"],
        ["fx", "fy", "torque"],
    )


def plant_dynamics(vehicle: Vehicle, road: RoadSurface, payload: bool = False):
    """SX expressions ``(x, u, xdot, y)`` of the plant on one road (see module docstring).

    With ``payload`` the input ends with :data:`PAYLOAD_INPUT_NAMES`: the sprung body
    carries that point mass (:func:`loaded_body_accelerations`); springs, preloads and
    geometry stay the file's, so the payload shows as static compression.
    """
    plant = vehicle_plant(vehicle)
    lookup = road_lookup(road)
    x = ca.SX.sym("x", len(STATE_NAMES))
    inp = ca.SX.sym("u", len(INPUT_NAMES) + (len(PAYLOAD_INPUT_NAMES) if payload else 0))
    s, n, z, phi, theta, psi = (x[i] for i in range(6))
    vel = x[6:9]
    omega = x[9:12]
    d, dd, spin, kappa, alpha = x[12:16], x[16:20], x[20:24], x[24:28], x[28:32]
    steer = inp[0]
    drive, brake = inp[1:5], inp[5:9]

    m_s = vehicle.mass.sprung
    m = vehicle.mass.total
    inertia = ca.DM(vehicle.mass.inertia)  # principal axes
    rot = _rotation(phi, theta, psi)
    g_body = rot.T @ ca.DM([0.0, 0.0, -GRAVITY])
    curvature = lookup(s)[3]

    items = corners(vehicle)
    tyre = plant.tyre
    susp = vehicle.suspension
    arb = []
    for axle, setting in enumerate((susp.front, susp.rear)):
        arb.extend(
            anti_roll_bar_forces(d[2 * axle], d[2 * axle + 1], setting.arb_rate, setting.arb_ratio)
        )

    tyre_vectors, contacts, centres, susp_forces, fz_list, wheel_terms = [], [], [], [], [], []
    for i, c in enumerate(items):
        r_w = ca.vertcat(c.x, c.y, c.z_static + d[i])
        offset = rot @ r_w
        n_i = n + offset[1]
        s_i = s + offset[0] / (1.0 - curvature * n)
        row = lookup(s_i)
        elevation, grade, bank = row[0], row[1], row[2]
        rough = row[4] if c.left else row[5]
        slope_norm = ca.sqrt(1.0 + grade**2 + bank**2)
        normal_path = ca.vertcat(-grade, -bank, 1.0) / slope_norm
        normal = rot.T @ normal_path
        gap = (z + offset[2] - (elevation + n_i * bank + rough)) / slope_norm
        deflection = c.radius - gap
        fz = c.tyre_rate * ca.fmax(deflection, 0.0)
        heading = ca.vertcat(ca.cos(steer), ca.sin(steer), 0.0) if i < 2 else ca.DM([1, 0, 0])
        e_x = _unit(heading - ca.dot(heading, normal) * normal)
        e_y = ca.cross(normal, e_x)
        v_w = vel + ca.cross(omega, r_w)
        vx_w, vy_w = ca.dot(v_w, e_x), ca.dot(v_w, e_y)
        fx, fy = tyre_forces(kappa[i], alpha[i], fz, c.nominal_load, tyre)
        force = fx * e_x + fy * e_y + fz * normal
        loaded = ca.fmin(gap, c.radius)
        effective_radius = rolling_radius(c.radius, ca.fmax(deflection, 0.0))
        spin_sign = spin_direction(spin[i])
        spin_acc = (
            wheel_torque(drive[i], brake[i], spin_sign)
            - fx * loaded
            - tyre.rolling_resistance * fz * loaded * spin_sign
        ) / c.spin_inertia
        kappa_dot = ((spin[i] * effective_radius - vx_w) - ca.fabs(vx_w) * kappa[i]) / (
            tyre.relaxation_length_x
        )
        alpha_dot = (-vy_w - ca.fabs(vx_w) * alpha[i]) / tyre.relaxation_length_y
        f_s = corner_suspension_force(c, d[i], dd[i], arb[i])
        # Vertical force of the links: lateral force through the roll centre,
        # longitudinal along the side-view anti-pitch line (module docstring).
        sign = -1.0 if i < 2 else 1.0
        tan_beta = ca.if_else(fx < 0, c.anti_brake, c.anti_drive)
        jack = -fy * c.roll_centre / c.y + sign * fx * tan_beta
        tyre_vectors.append(force)
        contacts.append(r_w - gap * normal)
        centres.append(r_w)
        susp_forces.append(f_s + jack)
        fz_list.append(fz)
        wheel_terms.append((spin_acc, kappa_dot, alpha_dot))

    aero = vehicle.aero
    pressure = 0.5 * aero.air_density * aero.reference_area * vel[0] ** 2
    drag = pressure * aero.drag_coefficient * ca.tanh(vel[0] / SPIN_SMOOTHING)
    lift = pressure * aero.lift_coefficient
    f_aero = ca.vertcat(-drag, 0.0, lift)
    r_aero = ca.DM(aero.application_point)

    tyre_sum = sum(tyre_vectors[1:], tyre_vectors[0])
    coriolis = ca.cross(omega, vel)

    def corner_moment(acc):
        moment = ca.cross(r_aero, f_aero)
        for i, c in enumerate(items):
            link = ca.vertcat(
                tyre_vectors[i][0:2] + c.unsprung * (g_body[0:2] - acc[0:2]), susp_forces[i]
            )
            moment += ca.cross(centres[i], link) + ca.cross(
                contacts[i] - centres[i], tyre_vectors[i]
            )
        return moment

    if payload:
        force = ca.vertcat(tyre_sum[0:2] + f_aero[0:2], sum(susp_forces) + lift)
        in_plane = ca.diag(ca.DM([1.0, 1.0, 0.0]))
        unsprung = sum(c.unsprung * _skew(centres[i]) @ in_plane for i, c in enumerate(items))
        acc, omega_dot = loaded_body_accelerations(
            vehicle, inp[len(INPUT_NAMES) :], force, corner_moment(ca.DM.zeros(3)), unsprung,
            omega, g_body,
        )  # fmt: skip
    else:
        acc_xy = (tyre_sum[0:2] + f_aero[0:2]) / m + g_body[0:2]
        acc_z = (sum(susp_forces) + lift) / m_s + g_body[2]
        acc = ca.vertcat(acc_xy, acc_z)  # kinematic acceleration of the sprung CG
        omega_dot = (corner_moment(acc) - ca.cross(omega, inertia * omega)) / inertia

    d_ddot = []
    for i, c in enumerate(items):
        r_w = centres[i]
        carried = acc + ca.cross(omega_dot, r_w) + ca.cross(omega, ca.cross(omega, r_w))
        d_ddot.append(
            (tyre_vectors[i][2] + c.unsprung * g_body[2] - susp_forces[i]) / c.unsprung - carried[2]
        )

    path_velocity = rot @ vel
    s_dot = path_velocity[0] / (1.0 - n * curvature)
    phi_dot = omega[0] + (omega[1] * ca.sin(phi) + omega[2] * ca.cos(phi)) * ca.tan(theta)
    theta_dot = omega[1] * ca.cos(phi) - omega[2] * ca.sin(phi)
    psi_dot = (omega[1] * ca.sin(phi) + omega[2] * ca.cos(phi)) / ca.cos(theta) - curvature * s_dot
    xdot = ca.vertcat(
        s_dot,
        path_velocity[1],
        path_velocity[2],
        phi_dot,
        theta_dot,
        psi_dot,
        acc - coriolis,
        omega_dot,
        dd,
        ca.vertcat(*d_ddot),
        ca.vertcat(*[t[0] for t in wheel_terms]),
        ca.vertcat(*[t[1] for t in wheel_terms]),
        ca.vertcat(*[t[2] for t in wheel_terms]),
    )
    imu = ca.DM(vehicle.geometry.imu_position)
    imu_acc = acc + ca.cross(omega_dot, imu) + ca.cross(omega, ca.cross(omega, imu)) - g_body
    roll, pitch, yaw = vehicle.geometry.imu_orientation
    to_sensor = (rotation_z(yaw) @ rotation_y(pitch) @ rotation_x(roll)).T
    hub = [
        (tyre_vectors[i][2] - susp_forces[i]) / c.unsprung for i, c in enumerate(items)
    ]  # m_u (a_hub - g_z) = F_t,z - F_s - J: the hub's specific force along body z
    y = ca.vertcat(
        ca.vertcat(*fz_list), to_sensor @ imu_acc, acc, ca.vertcat(*hub), to_sensor @ omega
    )
    return x, inp, xdot, y


def rk4_function(ode: ca.Function, name: str) -> ca.Function:
    r"""``name(x, u, dt) -> x_next``: one classical RK4 step of ``ode(x, u) -> (xdot, ...)``.

    .. math:: x^+ = x + \tfrac{h}{6}(k_1 + 2 k_2 + 2 k_3 + k_4)

    with the input held over the step.
    """
    x = ca.SX.sym("x", ode.size1_in(0))
    inp = ca.SX.sym("u", ode.size1_in(1))
    dt = ca.SX.sym("dt")
    k1 = ode(x, inp)[0]
    k2 = ode(x + 0.5 * dt * k1, inp)[0]
    k3 = ode(x + 0.5 * dt * k2, inp)[0]
    k4 = ode(x + dt * k3, inp)[0]
    x_next = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function(name, [x, inp, dt], [x_next], ["x", "u", "dt"], ["x_next"])


def plant_functions(
    vehicle: Vehicle, road: RoadSurface, name: str = "plant", payload: bool = False
):
    """``(name_ode(x, u) -> (xdot, y), name_rk4(x, u, dt) -> x_next)`` as SX Functions
    (``payload``: :func:`plant_dynamics`)."""
    x, inp, xdot, y = plant_dynamics(vehicle, road, payload)
    ode = ca.Function(f"{name}_ode", [x, inp], [xdot, y], ["x", "u"], ["xdot", "y"])
    return ode, rk4_function(ode, f"{name}_rk4")


def chunk_from_ode(
    ode: ca.Function, internal_rate: float, steps: int, name: str, jit: bool = True
) -> ca.Function:
    """``name(x0, u) -> (x, y)``: ``steps`` RK4 steps of ``ode`` at ``internal_rate``, input held.

    ``y`` is the second output of ``ode`` at the final state. Compiled with
    the system C compiler when ``jit`` is true, once per model: the library is
    cached by the hash of its source
    (:func:`~wheelload.models.runtime.build_folder.cached_function`).
    """
    if internal_rate <= 0 or steps < 1:
        raise PlantError(f"need internal_rate > 0 and steps >= 1, got {internal_rate}, {steps}")
    rk4 = rk4_function(ode, f"{name}_rk4")
    dt = 1.0 / internal_rate
    x0 = ca.MX.sym("x0", ode.size1_in(0))
    inp = ca.MX.sym("u", ode.size1_in(1))
    accum = rk4.mapaccum(f"{name}_steps", steps)
    states = accum(x0, ca.repmat(inp, 1, steps), ca.repmat(dt, 1, steps))
    x_end = states[:, -1]
    y_end = ode(x_end, inp)[1]
    chunk = ca.Function(name, [x0, inp], [x_end, y_end], ["x0", "u"], ["x", "y"])
    return cached_function(chunk) if jit else chunk


def chunk_function(
    vehicle: Vehicle,
    road: RoadSurface,
    internal_rate: float,
    steps: int,
    jit: bool = True,
    payload: bool = False,
) -> ca.Function:
    """``plant_chunk(x0, u) -> (x, y)``: ``steps`` RK4 steps at ``internal_rate`` with input held.

    ``y`` holds :data:`OUTPUT_NAMES` at the final state. Compiled with the
    system C compiler when ``jit`` is true. With ``payload`` the input ends with
    :data:`PAYLOAD_INPUT_NAMES` (:func:`plant_dynamics`).
    """
    ode, _ = plant_functions(vehicle, road, payload=payload)
    return chunk_from_ode(ode, internal_rate, steps, "plant_chunk", jit)
