r"""Real circuits from the bundled track data (``studies/data/tracks``, see its README).

Centre lines: Hockenheim GP (TUMFTM racetrack-database, LGPL-3.0), Nürburgring
Nordschleife (OpenStreetMap relation 38566, ODbL 1.0), both clockwise (race
direction). Elevation: zaggyai track_data GPS polylines (MIT), projected to
local metres (equirectangular, :math:`x = R \Delta\lambda \cos\bar\varphi`,
:math:`y = R \Delta\varphi`), registered to the centre line by a rigid 2-D
fit (iterative closest point), mapped to the arc length of the nearest centre
line point and smoothed with a periodic Gaussian of standard deviation
:data:`ELEVATION_SMOOTHING` (200 m: an effective window of about 500 m, as the
data README asks for the noisy Nordschleife file; it keeps the real ±12 %
grades). Curvature :math:`\kappa = d\psi/ds` of the centre line resampled to
:data:`STEP`, smoothed over :data:`CURVATURE_SMOOTHING`. Bank is zero. The
Hockenheim half-width is the smaller of the left and right widths of the data;
the Nordschleife has no public width, a nominal :data:`NORDSCHLEIFE_HALF_WIDTH`
is used.
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial import cKDTree

from wheelload.studies.drive.roads import Road, build_road

EARTH_RADIUS = 6_371_000.0  # m
STEP = 1.0  # m, road grid spacing
LEAD_IN = 300.0  # m of track repeated before s = 0 and after the lap
NORDSCHLEIFE_HALF_WIDTH = 4.5  # m, nominal (no public width data)
ELEVATION_SMOOTHING = 200.0  # m, standard deviation of the Gaussian on elevation
CURVATURE_SMOOTHING = 5.0  # m, standard deviation of the Gaussian on curvature


def track_file(name: str) -> Path:
    return Path(str(resources.files("wheelload.studies") / "data" / "tracks" / name))


def _gps(name: str) -> np.ndarray:
    points = json.loads(track_file(name).read_text(encoding="utf-8"))["pts"]
    rows = np.array([[p["lat"], p["lon"], p["elev"]] for p in points], float)
    rows = rows[rows[:, 2] != 0.0]  # placeholder points
    lat, lon = np.radians(rows[:, 0] * 1e-7), np.radians(rows[:, 1] * 1e-7)
    east = EARTH_RADIUS * (lon - lon.mean()) * np.cos(lat.mean())
    north = EARTH_RADIUS * (lat - lat.mean())
    return np.column_stack([east, north, rows[:, 2] * 1e-3])


def register_points(points: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, float]:
    """Rigid 2-D fit of ``points`` onto ``line`` (ICP from four start headings); RMS residual."""
    tree = cKDTree(line)
    best = (None, np.inf)
    for start in np.radians([0.0, 90.0, 180.0, 270.0]):
        rot = np.array([[np.cos(start), -np.sin(start)], [np.sin(start), np.cos(start)]])
        moved = (points - points.mean(0)) @ rot.T + line.mean(0)
        for _ in range(60):
            _, index = tree.query(moved)
            target = line[index]
            a, b = moved - moved.mean(0), target - target.mean(0)
            u, _, vt = np.linalg.svd(a.T @ b)
            r = (u @ vt).T
            if np.linalg.det(r) < 0:
                continue
            moved = a @ r.T + target.mean(0)
        residual = float(np.sqrt(np.mean(tree.query(moved)[0] ** 2)))
        if residual < best[1]:
            best = (moved, residual)
    return best


def _periodic(values: np.ndarray, s: np.ndarray, length: float, grid: np.ndarray) -> np.ndarray:
    return np.interp(np.mod(grid, length), s, values, period=length)


def _elevation(gps_name: str, line: np.ndarray, s_line: np.ndarray, length: float):
    gps = _gps(gps_name)
    moved, residual = register_points(gps[:, :2], line)
    _, index = cKDTree(line).query(moved)
    s_points = s_line[index]
    order = np.argsort(s_points)
    grid = np.arange(0.0, length, STEP)
    z = np.interp(grid, s_points[order], gps[order, 2], period=length)
    z = gaussian_filter1d(z, ELEVATION_SMOOTHING / STEP, mode="wrap")
    return grid, z - z[0], residual


def _track_road(x, y, half_width, elevation_file) -> Road:
    """Road on a grid from -LEAD_IN to length + LEAD_IN (the lap repeated at both ends)."""
    closed_x, closed_y = np.r_[x, x[0]], np.r_[y, y[0]]
    s_raw = np.r_[0.0, np.cumsum(np.hypot(np.diff(closed_x), np.diff(closed_y)))]
    length = float(s_raw[-1])
    line = np.column_stack([x, y])
    grid, z, _ = _elevation(elevation_file, line, s_raw[:-1], length)
    xs = np.interp(grid, s_raw, closed_x)
    ys = np.interp(grid, s_raw, closed_y)
    heading = np.unwrap(np.arctan2(np.gradient(ys), np.gradient(xs)))
    curvature = gaussian_filter1d(
        np.gradient(heading, STEP), CURVATURE_SMOOTHING / STEP, mode="wrap"
    )
    width = np.interp(grid, s_raw[:-1], half_width)
    s = np.arange(-LEAD_IN, length + LEAD_IN, STEP)
    x_ext, y_ext = _periodic(xs, grid, length, s), _periodic(ys, grid, length, s)
    return build_road(
        s,
        curvature=_periodic(curvature, grid, length, s),
        elevation=_periodic(z, grid, length, s),
        half_width=_periodic(width, grid, length, s),
        centre_line=(x_ext, y_ext, np.unwrap(np.arctan2(np.gradient(y_ext), np.gradient(x_ext)))),
        length=length,
    )


@cache
def hockenheim() -> Road:
    """Hockenheim GP circuit, 4.57 km (columns ``x_m, y_m, w_tr_right_m, w_tr_left_m``)."""
    data = np.loadtxt(track_file("hockenheim_centerline_tumftm.csv"), delimiter=",", comments="#")
    half = np.minimum(data[:, 2], data[:, 3])
    return _track_road(data[:, 0], data[:, 1], half, "hockenheim_elevation_zaggyai.json")


@cache
def nordschleife() -> Road:
    """Nürburgring Nordschleife, 20.7 km (columns ``s_m, x_m, y_m, psi_rad, kappa_1pm``)."""
    data = np.loadtxt(track_file("nordschleife_centerline_osm.csv"), delimiter=",", skiprows=4)
    x, y = data[:, 1], data[:, 2]  # the last point is 3.5 m short of the first
    half = np.full_like(x, NORDSCHLEIFE_HALF_WIDTH)
    return _track_road(x, y, half, "nordschleife_btg_elevation_zaggyai.json")
