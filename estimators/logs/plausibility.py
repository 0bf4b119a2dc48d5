r"""Plausibility of what a channel map produces: the log against the vehicle file.

The wiring checks (:mod:`~wheelload.estimators.logs.checks`) test signs and
kinematic ratios; a scale that is wrong by a constant factor (a motion ratio,
a travel unit, a gear ratio, a time unit) keeps every sign and passes them.
These checks weigh the log against the vehicle file's own physics instead,
on the quasi-static samples of the first :data:`~log_checks.WINDOW` s of motion
(low-passed to :data:`~log_checks.CUTOFF`, as the wiring checks):

- **sample rate**: a median rate above :data:`MAX_RATE` or below
  :data:`MIN_RATE` is no vehicle logger (a time column declared ``ms`` while in
  seconds makes 100 Hz a 100 kHz log);
- **corner travel**: a travel whose spring force would carry the whole vehicle,
  :math:`|d_i| k_i > m g` (the guards' plausibility range), on more than
  :data:`MAX_OUT_OF_RANGE` of the samples: a travel unit or motion ratio too
  large;
- **travel scale** (pitch and roll rows of the equilibrium, eq. 15-16): the
  travel's share of the pseudo-measured loads, :math:`x = A\,(z(d) - z(0))`,
  must balance what the accelerometer demands, :math:`y = b - A\,z(0)`; the
  slope :math:`\kappa` of :math:`x` on :math:`y` is 1 for the right travel and
  the factor of the mistake otherwise (motion ratio ten times or inverted, cm
  for mm);
- **aerodynamic lift** (vertical row): :math:`\sum_i z_i - m a_z` against the
  lift :math:`L(v_x) = \tfrac12\rho A c_L v_x^2` at the logged speed must have
  slope :math:`-1`, and at steady speed :math:`\sum_i z_i` must be the
  weight less the lift within :data:`MAX_WEIGHT_ERROR` (a payload, a travel
  sensor's zero): a speed twice the true one (a gear ratio half the true one)
  predicts four times the lift the travel shows;
- **front/rear consistency** of the travel responses: per wheel, the
  quasi-static travel per unit :math:`a_x, a_z` against
  :func:`~log_checks.travel_response` of the vehicle file; a better fit with
  the front and rear columns exchanged names them.

Each check passes, fails (a one-line error naming the channel, the likely
cause and the fix) or cannot decide (too little excitation: then a warning,
never a failure). ``--skip-wiring-checks`` skips these checks too.

Example
-------
>>> report = check_plausibility(signals, vehicle)
>>> raise_for_plausibility(report, signals.source)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.kernels import order_statistics
from wheelload.estimators.logs.checks import (
    EQUILIBRIUM_FUNCTION,
    GATES_FUNCTION,
    KINEMATIC_CORRELATION,
    MIN_STD,
    RATE,
    SUSPENSION_FUNCTION,
    Check,
    CheckReport,
    Outcome,
    WiringError,
    describe,
    load_regressors,
    motion_window,
    quasi_static,
    travel_response,
    undecided_check,
)
from wheelload.estimators.logs.own_clocks import on_imu_clock
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.inputs import WHEELS
from wheelload.models.runtime.function_library import compiled_function

MAX_RATE = 5000.0  # Hz, above it no vehicle logger of body and suspension signals
MIN_RATE = 20.0  # Hz, below it the body motion (1-3 Hz) and wheel hop are lost
MAX_OUT_OF_RANGE = 0.01  # share of samples with |d| k > m g
SCALE_LIMITS = (0.6, 1.6)  # travel scale kappa accepted (see module docstring)
LIFT_LIMITS = (0.5, 3.0)  # lift slope accepted, in units of the file's lift
MIN_LIFT_STD = 0.01  # of the weight: lift variation needed to fit its slope
MAX_WEIGHT_ERROR = 0.3  # of the weight: sum of the loads at steady speed
STEADY = 0.5  # m/s^2: |ax|, |ay| below this (low-passed) is steady driving
SWAP_MARGIN = 2.0  # the exchanged fit must be this many times better to be named
MIN_RESPONSE = 0.3  # relative spread of the expected front/rear responses to compare them
MIN_SECONDS = 4.0  # s of examined samples (no frozen travel) needed to decide
FROZEN_TIME = 0.5  # s a travel holds one value while driving: a dead or stuck sensor, not a map


@dataclass(frozen=True, kw_only=True)
class PlausibilityReport(CheckReport):
    """All plausibility checks and the mistakes they name."""

    mistakes: tuple[str, ...]


def _check(name: str, statistic: float, failed: bool, note: str) -> Check:
    outcome = Outcome.FAILED if failed else Outcome.PASSED
    return Check(name=name, statistic=statistic, outcome=outcome, note=note)


def sample_rate_check(t: np.ndarray) -> tuple[Check, str | None]:
    """The median sample rate against :data:`MIN_RATE`, :data:`MAX_RATE`."""
    rate = float(1.0 / order_statistics.median(np.diff(t)))
    name = "sample rate"
    if rate > MAX_RATE:
        return _check(name, rate, True, "Hz"), (
            f"the log runs at {rate:.4g} Hz, above {MAX_RATE:g} Hz: its time column is likely "
            f"in seconds but declared in ms or us (key 'time.unit' of the channel map): "
            "give the unit the logger writes"
        )
    if rate < MIN_RATE:
        return _check(name, rate, True, "Hz"), (
            f"the log runs at {rate:.4g} Hz, below {MIN_RATE:g} Hz: too slow for the body "
            "motion, or its time column is declared in a larger unit than it is "
            "(key 'time.unit' of the channel map)"
        )
    return _check(name, rate, False, "Hz"), None


def _inputs(q: dict[str, np.ndarray]) -> np.ndarray:
    """Quasi-static inputs (len(INPUTS), n): travel, specific force, speed; no rates, v = 0."""
    n = q["t"].size
    u = np.full((len(INPUTS), n), np.nan)
    for name in ("ax", "ay", "az", "vx", *(f"d_{w}" for w in WHEELS)):
        if name in q:
            u[INPUTS.index(name)] = q[name]
    for w in WHEELS:
        u[INPUTS.index(f"v_{w}")] = 0.0  # quasi-static: no damper force
    return u


def _rows(u: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``A`` (3 x 4), the pseudo-measured loads with and without the travel (4 x n), ``b``."""
    valid = np.isfinite(u).astype(float)
    gates = compiled_function(GATES_FUNCTION).map(valid, p)[0]
    u = np.nan_to_num(u)
    without = u.copy()
    without[[INPUTS.index(f"d_{w}") for w in WHEELS]] = 0.0
    suspension = compiled_function(SUSPENSION_FUNCTION).map
    (z,) = suspension(u, gates, p)
    (z0,) = suspension(without, gates, p)
    A, b = compiled_function(EQUILIBRIUM_FUNCTION).map(u, gates, p)
    return np.asarray(A)[:, :4], np.column_stack([z, z0]), np.asarray(b)


def _slope(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Slope of ``x`` on ``y`` through their means, and their correlation."""
    x, y = x - x.mean(), y - y.mean()
    scale = math.sqrt(float(x @ x) * float(y @ y))
    if not scale > 0.0:
        return math.nan, 0.0
    return float(x @ y) / float(y @ y), float(x @ y) / scale


def travel_scale_checks(
    A: np.ndarray, z: np.ndarray, z0: np.ndarray, b: np.ndarray, mass: float, height: float
) -> tuple[list[Check], list[str]]:
    """The travel scale kappa of the pitch and roll rows (module docstring)."""
    checks, mistakes = [], []
    x = A @ (z - z0)
    y = b - A @ z0
    for row, (name, axis) in enumerate((("pitch", "ax"), ("roll", "ay")), start=1):
        check = f"travel scale ({name} row)"
        if not np.std(y[row]) > mass * height * MIN_STD[axis]:
            checks.append(undecided_check(check, f"{axis} varies too little"))
            continue
        kappa, correlation = _slope(x[row], y[row])
        if not abs(correlation) >= KINEMATIC_CORRELATION:
            checks.append(undecided_check(check, f"travel and {axis} correlate too little", kappa))
            continue
        low, high = SCALE_LIMITS
        failed = not low <= kappa <= high
        checks.append(_check(check, kappa, failed, "travel moment / demanded moment, 1 expected"))
        if failed and kappa < 0:
            mistakes.append(
                f"the travel columns turn the {name} moment that {axis} demands the other way "
                f"({kappa:.2g} times it): a travel sign, or "
                + ("front and rear columns exchanged" if row == 1 else "left and right exchanged")
                + " (keys 'channels.d_*.source', 'channels.d_*.sign')"
            )
        elif failed:
            mistakes.append(
                f"the travel columns d_fl d_fr d_rl d_rr explain {kappa:.2g} times the {name} "
                f"moment that {axis} demands (1 expected): a travel unit or motion ratio off "
                f"by about {kappa:.2g} (keys 'channels.d_*.unit' and "
                "'channels.d_*.motion_ratio', damper travel / wheel travel, usually 0.5-1.2)"
            )
    return checks, mistakes


def travel_range_check(
    q: dict[str, np.ndarray], parameters: ModelParameters
) -> tuple[list[Check], list[str]]:
    """Per wheel, the share of samples whose spring force exceeds the weight."""
    checks, mistakes = [], []
    weight = parameters.mass * GRAVITY
    springs = (parameters.spring_front,) * 2 + (parameters.spring_rear,) * 2
    for wheel, spring in zip(WHEELS, springs, strict=True):
        name = f"d_{wheel}"
        if name not in q:
            continue
        share = float(np.mean(np.abs(q[name]) * float(spring) > weight))
        failed = share > MAX_OUT_OF_RANGE
        checks.append(_check(f"{name} range", share, failed, "share of samples |d| k > m g"))
        if failed:
            limit = 1000.0 * weight / float(spring)
            mistakes.append(
                f"column '{name}' exceeds {limit:.0f} mm (a spring force above the whole weight) "
                f"on {100 * share:.0f} % of the samples: a travel unit or motion ratio too large "
                "(keys 'channels.d_*.unit', 'channels.d_*.motion_ratio')"
            )
    return checks, mistakes


def lift_checks(
    q: dict[str, np.ndarray], z: np.ndarray, parameters: ModelParameters
) -> tuple[list[Check], list[str]]:
    """The lift's slope and the steady sum of the loads (module docstring)."""
    checks, mistakes = [], []
    weight = parameters.mass * GRAVITY
    lift = 0.5 * parameters.air_density * parameters.reference_area
    lift = lift * parameters.lift_coefficient * q["vx"] ** 2
    shown = np.sum(z, axis=0) - parameters.mass * q["az"]  # -lift the travel shows
    name = "lift against speed"
    if not np.std(lift) > MIN_LIFT_STD * weight:
        checks.append(undecided_check(name, "speed (lift) varies too little"))
    else:
        slope, correlation = _slope(-shown, lift)
        if not correlation >= KINEMATIC_CORRELATION:
            checks.append(undecided_check(name, "travel and lift correlate too little", slope))
        else:
            low, high = LIFT_LIMITS
            failed = not low <= slope <= high
            checks.append(_check(name, slope, failed, "lift the travel shows / file's lift"))
            if failed:
                mistakes.append(_speed_mistake(slope))
    steady = (np.abs(q["ax"]) < STEADY) & (np.abs(q["ay"]) < STEADY)
    name = "loads at steady speed"
    if not steady.any():
        checks.append(undecided_check(name, "no steady driving"))
        return checks, mistakes
    error = float(
        order_statistics.median((np.sum(z, axis=0) - parameters.mass * q["az"] + lift)[steady])
    )
    failed = abs(error) > MAX_WEIGHT_ERROR * weight
    checks.append(_check(name, error / weight, failed, "(sum of loads - (m az - lift)) / m g"))
    if failed:
        mistakes.append(
            f"at steady speed the travel carries {error / weight:+.0%} of the weight beyond "
            "m az - lift (a payload or a sensor zero explains some percent): a travel unit or "
            "motion ratio (keys 'channels.d_*.unit', 'channels.d_*.motion_ratio'), or a speed "
            "that predicts the wrong lift (key 'channels.vx' or the wheel-speed 'ratio')"
        )
    return checks, mistakes


def _speed_mistake(slope: float) -> str:
    factor = 1.0 / math.sqrt(slope) if slope > 0 else math.nan
    return (
        f"the travel shows {slope:.2g} times the lift the file predicts at the logged speed: "
        f"the speed looks {factor:.2g} times the true one (a wheel-speed 'ratio' or 'radius', "
        "or the unit of 'channels.vx'), or the lift coefficient of the vehicle file is off"
    )


def front_rear_check(
    q: dict[str, np.ndarray], response: np.ndarray
) -> tuple[list[Check], list[str]]:
    """Per-wheel travel per unit ax and az (the lift's vx^2 held, :func:`load_regressors`)
    against the file's, and with front/rear exchanged."""
    name = "front/rear travel responses"
    if not all(f"d_{w}" in q for w in WHEELS):
        return [], []
    axes = [k for k, axis in enumerate(("ax", "ay", "az")) if np.std(q[axis]) > MIN_STD[axis]]
    axes = [k for k in axes if k != 1]  # roll travel is the same front and rear
    if not axes:
        return [undecided_check(name, "ax and az vary too little")], []
    expected = response[:, axes]
    spread = np.abs(expected[:2] - expected[2:]) / np.abs(expected).max(axis=0)
    if not np.any(spread > MIN_RESPONSE):
        return [undecided_check(name, "front and rear respond alike")], []
    _, regressors = load_regressors(q)  # ax, ay, az (used above), then vx^2
    X = np.column_stack([np.ones(q["t"].size), regressors])
    d = np.column_stack([q[f"d_{w}"] for w in WHEELS])
    coef, *_ = np.linalg.lstsq(X, d - d.mean(axis=0), rcond=None)
    measured = coef[1:][axes].T  # (4 wheels, axes)
    straight = float(np.sum((measured - expected) ** 2))
    exchanged = float(np.sum((measured[[2, 3, 0, 1]] - expected) ** 2))
    ratio = exchanged / max(straight, 1e-300)
    failed = straight > SWAP_MARGIN * exchanged
    check = _check(name, ratio, failed, "misfit exchanged / misfit as logged")
    if not failed:
        return [check], []
    return [check], [
        "the front travel columns respond as the rear ones should and the rear as the front "
        "(d_fl with d_rl, d_fr with d_rr look exchanged): check 'channels.d_*.source'"
    ]


def frozen_samples(t: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Samples at which any travel column (``d``: n x 4) holds one value for
    :data:`FROZEN_TIME` or longer: a dead or stuck sensor, which the fault monitor
    isolates; the checks of a channel map's scale leave those samples out."""
    frozen = np.zeros(t.size, bool)
    for column in d.T:
        change = np.flatnonzero(np.diff(column) != 0) + 1  # NaN != NaN: a change
        starts = np.concatenate([[0], change])
        stops = np.concatenate([change, [t.size]])
        for start, stop in zip(starts, stops, strict=True):
            if t[stop - 1] - t[start] >= FROZEN_TIME:
                frozen[start:stop] = True
    return frozen


def check_plausibility(signals, vehicle: Vehicle) -> PlausibilityReport:
    """Every check of the module docstring on a
    :class:`~wheelload.estimators.types.Signals`."""
    t, vx, acc, d = signals.t, signals.vx, signals.acc, signals.d
    if signals.own_clocks:  # channels on their own clocks: compared on the IMU's stamps
        t, vx, acc, d = on_imu_clock(t, acc, vx, acc, d)
    rate, mistake = sample_rate_check(t)
    checks, mistakes = [rate], [mistake] if mistake else []
    window = motion_window(t, vx)
    if window is None or mistake:
        checks.append(undecided_check("travel and speed", "less than 4 s of motion"))
        return PlausibilityReport(checks=tuple(checks), mistakes=tuple(mistakes))
    channels = {"vx": vx, "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2]}
    present = signals.travel_present
    channels.update({f"d_{w}": d[:, k] for k, w in enumerate(WHEELS) if present[k]})
    q = quasi_static(t[window], {k: v[window] for k, v in channels.items()})
    frozen = frozen_samples(t[window], d[window][:, present])
    if frozen.any():
        keep = ~np.isin(q["t"], t[window][frozen])
        q = {name: values[keep] for name, values in q.items()}
    if q["t"].size < MIN_SECONDS * RATE:
        checks.append(undecided_check("travel and speed", "a travel sensor holds one value"))
        return PlausibilityReport(checks=tuple(checks), mistakes=tuple(mistakes))
    parameters = ModelParameters.from_vehicle(vehicle)
    found = travel_range_check(q, parameters)
    checks += found[0]
    mistakes += found[1]
    if not all(f"d_{w}" in q for w in WHEELS) or not all(a in q for a in ("vx", "ax", "ay", "az")):
        note = "needs four travel channels, vx, ax, ay and az"
        checks.append(undecided_check("travel scale", note))
        return PlausibilityReport(checks=tuple(checks), mistakes=tuple(mistakes))
    A, loads, b = _rows(_inputs(q), parameters.vector())
    n = q["t"].size
    z, z0 = loads[:, :n], loads[:, n:]
    for found in (
        travel_scale_checks(A, z, z0, b, parameters.mass, parameters.cg_height),
        lift_checks(q, z, parameters),
        front_rear_check(q, travel_response(vehicle)),
    ):
        checks += found[0]
        mistakes += found[1]
    return PlausibilityReport(checks=tuple(checks), mistakes=tuple(mistakes))


def describe_plausibility(report: PlausibilityReport) -> str:
    """One line: how many checks passed, which could not decide (and why)."""
    return describe(report, title="plausibility checks (log against the vehicle file)")


def raise_for_plausibility(report: PlausibilityReport, source: str) -> None:
    """One-line :class:`WiringError` naming the mistake, if any check failed."""
    if report.mistakes:
        raise WiringError(
            f"{source}: plausibility check: {'; and '.join(report.mistakes)}; "
            "if the log is right, give --skip-wiring-checks"
        )
