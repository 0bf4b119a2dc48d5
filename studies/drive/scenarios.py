"""The papers' scenarios as runs of the closed-loop simulation.

| name | source | what |
| --- | --- | --- |
| iso-dlc | main paper §IV-C; ISO 3888-1 | double lane change, 80 km/h entry |
| brake-in-turn, accel-in-turn | combined-slip checks | 100 m / 60 m turns; ``beyond_grip`` |
| bounce-sweep | ycoo paper §5, Fig. 6 | sine bumps, wavelength down to 1.6 m at 20 km/h |
| slope-20 | ycoo paper Fig. 7 | flat road onto a 20 % grade |
| chicane-bank-30 | road-angle paper §V | ±0.5 g chicane at 30 km/h, 30 % bank |
| chicane-incline-20 | road-angle paper §V | the same on a 20 % incline |
| wheel-lift | this project | 0.8 g turn; the inner wheels cross a kerb and lift off |
| standstill | ycoo paper §5 | held at rest for 5 s on a plane of ``grade`` and ``bank`` (options) |
| stop-and-go | this project | 10 s at rest (a passenger gets in), then 80 km/h and a lane change |
| hockenheim | main paper Table IV; issue 4 | flying lap of the Hockenheim GP circuit, 4.57 km |
| nordschleife | main paper Table III; issue 4 | flying lap of the Nordschleife, 20.7 km |

``beyond_grip`` (:class:`~wheelload.studies.drive.scenario_options.BeyondGrip`): the turns'
speed change asked beyond a low-μ road's grip, the ABS / TCS cycling past the force peak.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from wheelload.models.conventions import GRAVITY
from wheelload.models.plant.dynamics import vehicle_plant
from wheelload.models.vehicle.description import Vehicle
from wheelload.studies.drive import laps
from wheelload.studies.drive.roads import Road, build_road, iso8608_profile, smooth_step
from wheelload.studies.drive.scenario_names import SCENARIO_NAMES
from wheelload.studies.drive.scenario_options import BeyondGrip, Options
from wheelload.studies.drive.simulation import Run

KMH = 1.0 / 3.6
GRID = 0.25  # m, road table spacing of the short scenarios


#: The roughness fades in (cosine ramp) from RUN_IN[0] to RUN_IN[0] + RUN_IN[1] metres after
#: the road's start, so that the car starts in steady motion on a smooth road: on a class D
#: road a wheel could otherwise find no steady contact at the start.
RUN_IN = (3.0, 10.0)


def _rough(s: np.ndarray, vehicle: Vehicle, options: Options) -> tuple | None:
    if options.roughness is None:
        return None
    model = vehicle_plant(vehicle).roughness
    rng = np.random.default_rng(np.random.SeedSequence([options.seed, 8608]))
    fade = smooth_step(s, s[0] + RUN_IN[0], RUN_IN[1])
    return tuple(fade * iso8608_profile(s, options.roughness, model, rng) for _ in range(2))


def _constant(road: Road, speed: float) -> np.ndarray:
    return np.full_like(road.s, speed)


def dlc_lanes(vehicle: Vehicle, entry: float = 100.0):
    """ISO 3888-1 lanes: (start, end, centre offset, width) of sections 1, 3, 5 [m]."""
    width = vehicle_plant(vehicle).body.width
    return (
        (entry, entry + 15.0, 0.0, 1.1 * width + 0.25),
        (entry + 45.0, entry + 70.0, 3.5, 1.2 * width + 0.25),
        (entry + 95.0, entry + 125.0, 0.0, 1.3 * width + 0.25),
    )


def _dlc_target(s: np.ndarray, entry: float) -> np.ndarray:
    """Target path of the double lane change whose first lane starts at ``entry``."""
    return 3.5 * (smooth_step(s, entry + 12.0, 36.0) - smooth_step(s, entry + 67.0, 32.0))


def iso_dlc(vehicle: Vehicle, options: Options) -> Run:
    """Double lane change: sections 15/30/25/25/15/15 m, lane 3 offset 3.5 m to the left.

    The target path leaves each lane and enters the next with cosine ramps
    that start 3 m before a lane ends and finish 3 m inside the next (0.1 m
    from the lane centre there, inside the cone margins), as a driver cuts the
    transition.
    """
    entry = 100.0
    s = np.arange(0.0, 400.0, GRID)
    target = _dlc_target(s, entry)
    road = build_road(s, target=target, half_width=3.5 + 5.0, roughness=_rough(s, vehicle, options))
    return Run(
        road=road, speed=_constant(road, 80.0 * KMH), start=0.0, stop=entry + 200.0, max_time=20.0
    )


def _turn(vehicle: Vehicle, options: Options, radius: float, length: float) -> Road:
    s = np.arange(0.0, length, GRID)
    curvature = smooth_step(s, 30.0, 20.0) / radius
    return build_road(s, curvature=curvature, half_width=5.0, roughness=_rough(s, vehicle, options))


def _speed_change(
    s: np.ndarray, at: float, speeds: tuple[float, float], rate: float, beyond: BeyondGrip | None
) -> np.ndarray:
    """Speed target: ``speeds[0]`` until ``at``, then changing at ``rate`` to ``speeds[1]``;
    with ``beyond`` both speeds scaled and the rate its own (:class:`BeyondGrip`)."""
    if beyond is not None:
        speeds = (beyond.speed_scale * speeds[0], beyond.speed_scale * speeds[1])
        rate = beyond.speed_rate
    sign = 1.0 if speeds[1] > speeds[0] else -1.0
    low, high = sorted(speeds)
    return np.sqrt(np.clip(speeds[0] ** 2 + sign * 2.0 * rate * (s - at), low**2, high**2))


def _beyond_grip(run: Run, beyond: BeyondGrip | None) -> Run:
    """``run`` with the driver's assumed friction and the slip control of ``beyond``."""
    if beyond is None:
        return run
    tuning = replace(run.tuning, assumed_friction=beyond.driver_friction)
    return replace(run, tuning=tuning, slip_control=beyond.slip_control)


def brake_in_turn(vehicle: Vehicle, options: Options) -> Run:
    """Steady 0.4 g on a 100 m left turn at 20 m/s, then braking at 5 m/s^2 to 8 m/s.

    With ``options.beyond_grip`` (:class:`BeyondGrip`): slower, braking beyond the grip.
    """
    road = _turn(vehicle, options, 100.0, 500.0)
    speed = _speed_change(road.s, 200.0, (20.0, 8.0), 5.0, options.beyond_grip)
    run = Run(road=road, speed=speed, start=0.0, stop=340.0, max_time=25.0)
    return _beyond_grip(run, options.beyond_grip)


def accel_in_turn(vehicle: Vehicle, options: Options) -> Run:
    """Steady 0.25 g on a 60 m left turn at 12 m/s, then accelerating at 3 m/s^2 to 19 m/s.

    With ``options.beyond_grip`` (:class:`BeyondGrip`): slower, accelerating beyond the grip.
    """
    road = _turn(vehicle, options, 60.0, 400.0)
    speed = _speed_change(road.s, 120.0, (12.0, 19.0), 3.0, options.beyond_grip)
    run = Run(road=road, speed=speed, start=0.0, stop=300.0, max_time=25.0)
    return _beyond_grip(run, options.beyond_grip)


def bounce_sweep(vehicle: Vehicle, options: Options) -> Run:
    r"""Sine bumps on both tracks at 20 km/h, wavelength 20 m falling to ``min_wavelength``.

    The spatial frequency :math:`1/\lambda` rises linearly with distance (a
    linear chirp in time at constant speed); the amplitude
    :math:`\min(0.03, 0.005 \lambda)` keeps the road velocity amplitude at
    0.175 m/s once the cap is left.
    """
    speed = 20.0 * KMH
    start, sweep = 20.0, 20.0 * speed  # 20 s of sweep
    s = np.arange(0.0, start + sweep + 40.0, 0.05)
    low, high = 1.0 / 20.0, 1.0 / options.min_wavelength
    along = np.clip(s - start, 0.0, sweep)
    frequency = low + (high - low) * along / sweep
    phase = 2.0 * np.pi * (low * along + 0.5 * (high - low) * along**2 / sweep)
    amplitude = np.minimum(0.03, 0.005 / frequency) * (s > start) * (s < start + sweep)
    bumps = amplitude * np.sin(phase) * smooth_step(s, start, 2.0)
    road = build_road(s, elevation=bumps, half_width=5.0, roughness=_rough(s, vehicle, options))
    return Run(
        road=road, speed=_constant(road, speed), start=0.0, stop=start + sweep + 10.0, max_time=30.0
    )


def slope_20(vehicle: Vehicle, options: Options) -> Run:
    """Flat 60 m, a 15 m vertical curve, then 100 m of 20 % grade, at 30 km/h."""
    s = np.arange(0.0, 220.0, GRID)
    grade = 0.20 * smooth_step(s, 60.0, 15.0)
    elevation = np.concatenate([[0.0], np.cumsum(0.5 * (grade[1:] + grade[:-1]) * GRID)])
    road = build_road(s, elevation=elevation, half_width=5.0, roughness=_rough(s, vehicle, options))
    return Run(road=road, speed=_constant(road, 30.0 * KMH), start=0.0, stop=190.0, max_time=30.0)


def _chicane(vehicle: Vehicle, options: Options, bank: float, grade: float) -> Run:
    r"""Three periods of a sine weave of 40 m wavelength at 30 km/h: peak
    :math:`a_y = v^2 A (2\pi/\lambda)^2 = 0.5 g` with :math:`A = 2.02` m."""
    speed = 30.0 * KMH
    wavelength = 40.0
    amplitude = 0.5 * GRAVITY / (speed**2 * (2.0 * np.pi / wavelength) ** 2)
    s = np.arange(0.0, 200.0, GRID)
    weave = (s >= 30.0) & (s <= 30.0 + 3 * wavelength)
    target = amplitude * np.sin(2.0 * np.pi * (s - 30.0) / wavelength) * weave
    road = build_road(
        s,
        elevation=grade * s,
        bank=np.full_like(s, bank),
        target=target,
        half_width=6.0,
        roughness=_rough(s, vehicle, options),
    )
    # The plant starts in steady motion on the bank or grade
    # (models/plant/equilibrium.py): no lead-in to drop.
    return Run(road=road, speed=_constant(road, speed), start=0.0, stop=180.0, max_time=30.0)


def chicane_bank_30(vehicle: Vehicle, options: Options) -> Run:
    """Chicane on a 30 % bank (left edge higher, 16.7 deg)."""
    return _chicane(vehicle, options, bank=0.30, grade=0.0)


def chicane_incline_20(vehicle: Vehicle, options: Options) -> Run:
    """Chicane up a 20 % incline (11.3 deg)."""
    return _chicane(vehicle, options, bank=0.0, grade=0.20)


def wheel_lift(vehicle: Vehicle, options: Options) -> Run:
    """A 40 m left turn at 17 m/s (0.74 g); the inner (left) track crosses a kerb.

    The kerb is a 6 cm, 1.2 m long cosine hump under the left wheels only: it
    throws the already unloaded inner wheels off the road.
    """
    s = np.arange(0.0, 260.0, GRID)
    radius = 40.0
    curvature = smooth_step(s, 30.0, 25.0) / radius
    kerb_at = 130.0
    kerb = 0.06 * np.where(
        np.abs(s - kerb_at) < 0.6, 0.5 * (1 + np.cos(np.pi * (s - kerb_at) / 0.6)), 0.0
    )
    rough = _rough(s, vehicle, options)
    left = kerb if rough is None else kerb + rough[0]
    right = np.zeros_like(s) if rough is None else rough[1]
    road = build_road(s, curvature=curvature, half_width=5.0, roughness=(left, right))
    return Run(road=road, speed=_constant(road, 17.0), start=0.0, stop=200.0, max_time=20.0)


def standstill(vehicle: Vehicle, options: Options) -> Run:
    """Held at rest for 5 s on a plane of ``options.grade`` and ``options.bank``.

    The target speed is zero: the driver's speed control holds the car against
    the grade with drive torque (the plant's brakes fade below 0.5 rad/s of
    wheel spin), so it stands still to a creep of a few cm/s after the first
    second, with the tyres carrying the in-plane part of gravity.
    """
    s = np.arange(0.0, 100.0, GRID)
    road = build_road(
        s,
        elevation=options.grade * s,
        bank=np.full_like(s, options.bank),
        half_width=5.0,
        roughness=_rough(s, vehicle, options),
    )
    return Run(road=road, speed=np.zeros_like(s), start=50.0, stop=95.0, max_time=5.0)


#: stop-and-go: seconds at rest before driving off.
STOP_AND_GO_HOLD = 10.0


def stop_and_go(vehicle: Vehicle, options: Options) -> Run:
    """At rest for 10 s, then off at 2.5 m/s^2 to 80 km/h and the ISO double lane change.

    The car starts at s = 20 m; the lane change's first lane starts at 160 m (40 m of
    steady speed after the run-up), and the car drives on straight to 30 s after driving
    off. A payload change in the first 10 s (``wheelload simulate --payload-change``) is a
    passenger getting in at a stop.
    """
    start, entry, accel = 20.0, 160.0, 2.5
    s = np.arange(0.0, 700.0, GRID)
    road = build_road(
        s, target=_dlc_target(s, entry), half_width=3.5 + 5.0, roughness=_rough(s, vehicle, options)
    )
    speed = np.sqrt(np.clip(2.0 * accel * (s - start), 0.0, (80.0 * KMH) ** 2))
    return Run(
        road=road,
        speed=speed,
        start=start,
        stop=680.0,
        max_time=STOP_AND_GO_HOLD + 30.0,
        hold=STOP_AND_GO_HOLD,
    )


SCENARIOS: dict[str, Callable[[Vehicle, Options], Run]] = {
    "iso-dlc": iso_dlc,
    "brake-in-turn": brake_in_turn,
    "accel-in-turn": accel_in_turn,
    "bounce-sweep": bounce_sweep,
    "slope-20": slope_20,
    "chicane-bank-30": chicane_bank_30,
    "chicane-incline-20": chicane_incline_20,
    "wheel-lift": wheel_lift,
    "standstill": standstill,
    "stop-and-go": stop_and_go,
    "hockenheim": laps.hockenheim,
    "nordschleife": laps.nordschleife,
}
if tuple(SCENARIOS) != SCENARIO_NAMES:  # the table --help lists (scenario_names.py) is this one
    raise ImportError(f"scenarios {tuple(SCENARIOS)} differ from {SCENARIO_NAMES}")


#: The scenarios that take :attr:`Options.beyond_grip`: the paper's Table I turns on snow.
BEYOND_GRIP = ("brake-in-turn", "accel-in-turn")


def scenario_run(name: str, vehicle: Vehicle, options: Options | None = None) -> Run:
    """The :class:`Run` of a named scenario (default options), or an error listing the names."""
    options = Options() if options is None else options
    if name not in SCENARIOS:
        raise ValueError(f"unknown scenario '{name}'; choose from {', '.join(SCENARIOS)}")
    if options.beyond_grip is not None and name not in BEYOND_GRIP:
        raise ValueError(
            f"scenario '{name}' has no speed change beyond the grip; "
            f"beyond_grip applies to {', '.join(BEYOND_GRIP)}"
        )
    return SCENARIOS[name](vehicle, options)
