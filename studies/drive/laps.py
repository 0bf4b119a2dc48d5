"""Full laps of real circuits (issue 4): Hockenheim GP and the Nürburgring Nordschleife.

A flying lap on the centre line: the car starts :data:`RUN_IN` metres before
the start line at the profile's speed, the log starts at the line (``s = 0``)
and ends after one lap (or ``Options.shorten`` of one). The target speed is
the quasi-steady-state profile of :mod:`wheelload.studies.drive.speed_profile`,
planned with :data:`GRIP_MARGIN` of the tyres' cornering friction; the driver
is :class:`~wheelload.studies.drive.driver.Driver` with its default tuning. Track
data and licences: ``studies/data/tracks/README.md``.
"""

from __future__ import annotations

from wheelload.models.vehicle.description import Vehicle
from wheelload.studies.drive import tracks
from wheelload.studies.drive.roads import Road
from wheelload.studies.drive.scenario_options import Options
from wheelload.studies.drive.simulation import Run
from wheelload.studies.drive.speed_profile import lap_speed_profile

GRIP_MARGIN = 0.8  # -, share of the cornering friction the profile plans with
RUN_IN = 200.0  # m driven before the start line
LAP_TIME_LIMIT = 1.6  # -, max_time over a lap at the mean profile speed


def lap_run(vehicle: Vehicle, road: Road, options: Options) -> Run:
    """A flying lap (or ``options.shorten`` of one) of ``road`` at the lap speed profile."""
    if not 0.0 < options.shorten <= 1.0:
        raise ValueError(f"shorten must be in (0, 1], got {options.shorten}")
    speed = lap_speed_profile(vehicle, road, margin=GRIP_MARGIN)
    stop = options.shorten * road.length
    lap = (road.s >= 0.0) & (road.s <= road.length)
    expected = (stop + RUN_IN) / float(speed[lap].mean())
    return Run(
        road=road,
        speed=speed,
        start=-RUN_IN,
        stop=stop,
        max_time=LAP_TIME_LIMIT * expected + 10.0,
        record_from=0.0,
    )


def hockenheim(vehicle: Vehicle, options: Options) -> Run:
    """Hockenheim GP, 4.57 km, clockwise from the start line; TUMFTM centre line and widths."""
    return lap_run(vehicle, tracks.hockenheim(), options)


def nordschleife(vehicle: Vehicle, options: Options) -> Run:
    """Nürburgring Nordschleife, 20.7 km, clockwise; OSM centre line, 4.5 m nominal half-width."""
    return lap_run(vehicle, tracks.nordschleife(), options)
