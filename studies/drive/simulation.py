"""Closed-loop simulation: the compiled plant in chunks, the driver at the output rate.

Each output sample advances the plant and its wheel-slip control
(:mod:`wheelload.models.plant.slip_control`) by ``internal_rate / output_rate`` RK4
steps with the driver's requests held (a zero-order hold), then records the
true signals at the end of the chunk. ABS and traction control thus act at
the internal rate; path and speed control at the output rate.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from wheelload.models.conventions import WHEELS
from wheelload.models.plant.dynamics import (
    INPUT_NAMES,
    OUTPUT,
    OUTPUT_NAMES,
    STATE,
    STATE_NAMES,
    wheel_force_function,
)
from wheelload.models.plant.equilibrium import initial_state
from wheelload.models.plant.slip_control import FACTOR_NAMES, SlipControl, controlled_chunk_function
from wheelload.models.runtime import interrupts
from wheelload.models.vehicle.description import Vehicle
from wheelload.studies.drive.driver import Driver, DriverTuning
from wheelload.studies.drive.payload_schedule import PayloadSchedule
from wheelload.studies.drive.roads import Road


class SimulationError(RuntimeError):
    """The plant left its valid range (non-finite state, or off the road table)."""


@dataclass(frozen=True, kw_only=True)
class Run:
    """What to simulate: a road, a target speed on it, where to start and stop."""

    road: Road
    speed: np.ndarray  # m/s on the road grid
    start: float  # m, arc length at t = 0
    stop: float  # m, arc length that ends the run
    max_time: float  # s
    record_from: float | None = None  # m, drop samples before this arc length
    hold: float = 0.0  # s, the driver holds the car at rest this long before driving

    @property
    def stands_until(self) -> float:
        """Time [s] until which the car stands still: the whole run if no speed is asked."""
        return self.max_time if not np.any(self.speed) else self.hold

    tuning: DriverTuning = DriverTuning()
    slip_control: SlipControl = SlipControl()


@dataclass(frozen=True, kw_only=True)
class Truth:
    """True signals at the output rate, and the wall time spent."""

    frame: pd.DataFrame
    wall_time: float
    build_time: float
    # The plant's slip state on the frame's samples: transient slip ratios ``kappa_*`` and
    # the slip control's torque factors ``slip_factor_*`` (not logged: no sensor sees them).
    slip: pd.DataFrame | None = None


def simulate(
    vehicle: Vehicle,
    run: Run,
    *,
    internal_rate: float = 1000.0,
    output_rate: float = 100.0,
    payload: PayloadSchedule | None = None,
) -> Truth:
    """Drive the plant along ``run``; return the true signals (see :func:`truth_columns`).

    With ``payload`` the plant's sprung body carries it (the vehicle file keeps its
    springs and preloads: the payload shows as static compression); a change must fall
    where the car stands still (:attr:`Run.stands_until`), else a ``ValueError`` names
    its time.
    """
    steps = internal_rate / output_rate
    if abs(steps - round(steps)) > 1e-9 or steps < 1:
        raise ValueError(
            f"internal rate {internal_rate} Hz must be a multiple of output rate {output_rate} Hz"
        )
    moving = None if payload is None else payload.moving()
    if moving is not None and moving[1] > run.stands_until:
        latest = run.stands_until - (moving[1] - moving[0])
        hint = (
            f"choose a change time <= {latest:g} s"
            if latest >= 0.0
            else "the car never stands still here: use the standstill or stop-and-go scenario"
        )
        raise ValueError(
            f"the payload changes from t = {moving[0]:g} s to {moving[1]:g} s, but the car "
            f"stands still only until t = {run.stands_until:g} s: {hint}"
        )
    tic = time.perf_counter()
    if payload == PayloadSchedule():
        payload = None  # nothing on board: the plant of the file itself
    chunk = controlled_chunk_function(
        vehicle,
        run.road.surface,
        run.slip_control,
        internal_rate,
        int(round(steps)),
        payload=payload is not None,
    )
    initial = None if payload is None else payload.initial
    build_time = time.perf_counter() - tic
    speed0 = float(np.interp(run.start, run.road.s, run.speed))
    target0 = float(np.interp(run.start, run.road.s, run.road.target))
    dt = 1.0 / output_rate
    # Start in steady motion under the driver's first request; the request
    # depends on the start (heading, rates), so solve twice with fresh drivers.
    x = initial_state(vehicle, run.road.surface, run.start, speed0, target0, solve=False)
    for _ in range(2):
        probe = Driver(
            vehicle=vehicle, road=run.road, speed=run.speed, tuning=run.tuning, hold=run.hold
        )
        request = probe.inputs(x, dt)
        x = initial_state(
            vehicle, run.road.surface, run.start, speed0, target0, request=request, payload=initial
        )
    driver = Driver(
        vehicle=vehicle, road=run.road, speed=run.speed, tuning=run.tuning, hold=run.hold
    )
    z = np.concatenate([x, np.ones(len(FACTOR_NAMES))])
    count = int(np.ceil(run.max_time * output_rate))
    n_x, n_y = len(STATE_NAMES), len(OUTPUT_NAMES)
    states = np.empty((count, n_x))
    outputs = np.empty((count, n_y))
    inputs = np.empty((count, len(INPUT_NAMES)))
    factors = np.empty((count, len(FACTOR_NAMES)))
    s_limit = run.road.s[-1] - 10.0
    recorded = 0
    tic = time.perf_counter()
    for k in range(count):
        interrupts.check()  # a Ctrl-C the plant's CasADi call swallowed
        request = driver.inputs(z[:n_x], dt)
        if payload is not None:
            request = np.concatenate([request, payload.at(k * dt)])
        z_dm, y_dm = chunk(z, request)
        z, y = z_dm.full().ravel(), y_dm.full().ravel()
        states[k], outputs[k], inputs[k] = z[:n_x], y[:n_y], y[n_y : n_y + len(INPUT_NAMES)]
        factors[k] = z[n_x:]
        recorded = k + 1
        if not np.all(np.isfinite(z)):
            raise SimulationError(f"plant state not finite at t = {(k + 1) * dt:.3f} s")
        if z[STATE["s"]] >= min(run.stop, s_limit):
            break
    wall = time.perf_counter() - tic
    frame = truth_frame(states[:recorded], outputs[:recorded], inputs[:recorded], dt, run.road)
    frame = frame.assign(**wheel_columns(vehicle, states[:recorded], outputs[:recorded],
                                         inputs[:recorded]))  # fmt: skip
    slip = slip_frame(states[:recorded], factors[:recorded])
    if run.record_from is not None:
        kept = (frame["s"] >= run.record_from).to_numpy()
        frame = frame[kept].reset_index(drop=True)
        frame["t"] -= frame["t"].iloc[0]
        slip = slip[kept].reset_index(drop=True)
    return Truth(frame=frame, wall_time=wall, build_time=build_time, slip=slip)


def slip_frame(states: np.ndarray, factors: np.ndarray) -> pd.DataFrame:
    """The plant's transient slip ratios and the slip control's torque factors per wheel."""
    columns = {f"kappa_{w}": states[:, STATE[f"kappa_{w}"]] for w in WHEELS}
    columns.update({name: factors[:, i] for i, name in enumerate(FACTOR_NAMES)})
    return pd.DataFrame(columns)


def truth_frame(
    states: np.ndarray, outputs: np.ndarray, inputs: np.ndarray, dt: float, road: Road
) -> pd.DataFrame:
    """Log columns (clean) plus path columns ``s n psi target steer`` and CG accelerations.

    ``inputs`` are the inputs applied to the plant (after slip control).
    """
    frame = {"t": dt * np.arange(1, len(states) + 1), "vx": states[:, STATE["u"]]}
    for axis in ("ax", "ay", "az"):
        frame[axis] = outputs[:, OUTPUT[axis]]
    for axis in ("wx", "wy", "wz"):  # IMU sensor axes
        frame[axis] = outputs[:, OUTPUT[axis]]
    for prefix, state in (("d", "d"), ("v", "dd")):
        for wheel in WHEELS:
            frame[f"{prefix}_{wheel}"] = states[:, STATE[f"{state}_{wheel}"]]
    for wheel in WHEELS:
        frame[f"az_{wheel}"] = outputs[:, OUTPUT[f"az_{wheel}"]]
    for wheel in WHEELS:
        frame[f"fz_{wheel}"] = outputs[:, OUTPUT[f"fz_{wheel}"]]
    for key in ("s", "n", "psi", "phi", "theta", "z", "v"):
        frame[key if key != "v" else "vy"] = states[:, STATE[key]]
    for axis in ("ax_cg", "ay_cg", "az_cg"):
        frame[axis] = outputs[:, OUTPUT[axis]]
    frame["target"] = np.interp(frame["s"], road.s, road.target)
    frame["half_width"] = np.interp(frame["s"], road.s, road.half_width)
    frame["steer"] = inputs[:, 0]
    return pd.DataFrame(frame)


def wheel_columns(
    vehicle: Vehicle, states: np.ndarray, outputs: np.ndarray, inputs: np.ndarray
) -> dict[str, np.ndarray]:
    """Reference tyre forces ``fx_* fy_*`` [N] (tyre frame, ISO 8855: x along the wheel
    heading in the road plane, y to its left), wheel spins ``omega_*`` [rad/s] and the
    drive/brake torque on each wheel ``torque_*`` [N m, > 0 forward], from the plant's
    own equations (:func:`~wheelload.models.plant.dynamics.wheel_force_function`)."""

    def block(prefix: str) -> np.ndarray:
        return states[:, [STATE[f"{prefix}_{w}"] for w in WHEELS]].T

    fz = outputs[:, [OUTPUT[f"fz_{w}"] for w in WHEELS]].T
    drive = inputs[:, [INPUT_NAMES.index(f"drive_{w}") for w in WHEELS]].T
    brake = inputs[:, [INPUT_NAMES.index(f"brake_{w}") for w in WHEELS]].T
    spin = block("omega")
    count = states.shape[0]
    if count == 0:
        fx = fy = torque = np.zeros((4, 0))
    else:
        forces = wheel_force_function(vehicle).map(count)
        fx, fy, torque = (np.asarray(o).reshape(4, count) for o in forces(
            block("kappa"), block("alpha"), fz, spin, drive, brake))  # fmt: skip
    columns = {}
    for prefix, values in (("fx", fx), ("fy", fy), ("omega", spin), ("torque", torque)):
        columns.update({f"{prefix}_{w}": values[i] for i, w in enumerate(WHEELS)})
    return columns
