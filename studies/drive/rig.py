r"""Component rig on the plant's own suspension force elements (spring, damper map, stops, bar).

A corner rig strokes one corner's spring-damper unit with a sine sweep
:math:`d(t) = A \sin\phi(t)`, :math:`\dot\phi = 2\pi f(t)` with the
frequency rising linearly from ``f_low`` to ``f_high``, and records the
force change from static,
:math:`F = F_s(d, \dot d) - F_{pre}` of
:func:`wheelload.models.plant.dynamics.corner_suspension_force` (the bar left
untwisted). A bar rig moves the two wheels of an axle with sines of two
frequencies and records the load the plant's bar adds to the left wheel.
Load-cell and travel noise are white and Gaussian. The files are those
:mod:`wheelload.estimators.identification.data` reads.

Example
-------
>>> corners, bars = rig_sweep(load_vehicle(example_vehicle_path()), RigSettings())
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import pandas as pd

from wheelload.estimators.logs.output_files import check_outputs, write_text
from wheelload.models.conventions import AXLES, WHEELS
from wheelload.models.plant.dynamics import corner_suspension_force, corners
from wheelload.models.suspension.elements import anti_roll_bar_forces
from wheelload.models.vehicle.description import Vehicle


@dataclass(frozen=True, kw_only=True)
class RigSettings:
    duration: float = 40.0  # s per corner and per axle
    rate: float = 200.0  # Hz
    amplitude: float = 0.020  # m, stroke amplitude (inside the bump-stop gaps)
    f_low: float = 0.2  # Hz
    f_high: float = 8.0  # Hz, 1.0 m/s peak at 20 mm
    force_noise: float = 10.0  # N, 1 sigma load cell
    travel_noise: float = 0.02e-3  # m, 1 sigma
    seed: int = 0


def _sweep(settings: RigSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(0.0, settings.duration, 1.0 / settings.rate)
    slope = (settings.f_high - settings.f_low) / settings.duration
    frequency = settings.f_low + slope * t
    phase = 2 * np.pi * (settings.f_low * t + 0.5 * slope * t**2)
    d = settings.amplitude * np.sin(phase)
    v = settings.amplitude * 2 * np.pi * frequency * np.cos(phase)
    return t, d, v


def corner_force_function(vehicle: Vehicle, wheel: int) -> ca.Function:
    """``rig_corner(d, v) -> F``: the plant corner's force change from static [N]."""
    corner = corners(vehicle)[wheel]
    d, v = ca.SX.sym("d"), ca.SX.sym("v")
    force = corner_suspension_force(corner, d, v, 0) - corner_suspension_force(corner, 0, 0, 0)
    return ca.Function("rig_corner", [d, v], [force], ["d", "v"], ["F"])


def bar_force_function(vehicle: Vehicle, axle: int) -> ca.Function:
    """``rig_bar(d_left, d_right) -> F``: load the plant's bar adds to the left wheel [N]."""
    setting = (vehicle.suspension.front, vehicle.suspension.rear)[axle]
    left, right = ca.SX.sym("d_left"), ca.SX.sym("d_right")
    force = anti_roll_bar_forces(left, right, setting.arb_rate, setting.arb_ratio)[0]
    return ca.Function("rig_bar", [left, right], [force], ["d_left", "d_right"], ["F"])


def _record(t, key: str, name: str, travels: dict, force) -> pd.DataFrame:
    """One rig record: time, which corner or axle, the measured travels and force."""
    return pd.DataFrame({"t": t, key: name, **travels, "force": force})


def rig_sweep(vehicle: Vehicle, settings: RigSettings) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Corner-rig and bar-rig records of all four corners and both axles."""
    rng = np.random.default_rng(np.random.SeedSequence([settings.seed, 4711]))
    t, d, v = _sweep(settings)
    n = t.size
    noisy = lambda x, scale: x + scale * rng.standard_normal(n)  # noqa: E731
    corner_frames = []
    for wheel, name in enumerate(WHEELS):
        force = np.asarray(corner_force_function(vehicle, wheel).map(n)(d, v)).ravel()
        travels = {"d": noisy(d, settings.travel_noise), "v": v}
        corner_frames.append(
            _record(t, "corner", name, travels, noisy(force, settings.force_noise))
        )
    bar_frames = []
    for axle, name in enumerate(AXLES):
        left = settings.amplitude * np.sin(2 * np.pi * 0.5 * t)
        right = settings.amplitude * np.sin(2 * np.pi * 0.8 * t + 1.0)
        force = np.asarray(bar_force_function(vehicle, axle).map(n)(left, right)).ravel()
        travels = {
            "d_left": noisy(left, settings.travel_noise),
            "d_right": noisy(right, settings.travel_noise),
        }
        bar_frames.append(_record(t, "axle", name, travels, noisy(force, settings.force_noise)))
    return pd.concat(corner_frames, ignore_index=True), pd.concat(bar_frames, ignore_index=True)


def bar_file_path(corner_path: str | Path) -> Path:
    """The bar-rig file written beside a corner-rig file: ``<stem>_arb<suffix>``."""
    path = Path(corner_path)
    return path.with_name(f"{path.stem}_arb{path.suffix}")


def write_rig(
    corner: pd.DataFrame, bar: pd.DataFrame, path: str | Path, *, force: bool = False
) -> tuple[Path, Path]:
    """Write both rig files (an existing file only with ``force``); return their paths."""
    path = Path(path)
    if path.suffix.lower() != ".csv":
        raise ValueError(f"rig file '{path}' must end in .csv")
    targets = (path, bar_file_path(path))
    check_outputs(targets, [], force=force)
    header = "# wheelload rig sweep on the plant's suspension force elements (SI units)\n"
    for frame, target in zip((corner, bar), targets):
        text = header + frame.to_csv(index=False, float_format="%.9g")
        write_text(target, text, replace=force)
    return targets
