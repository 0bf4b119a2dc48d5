r"""Sign, unit and wiring checks of a log, from the correlations the physics demands.

Over the first :data:`WINDOW` seconds of motion, every channel is cleared of
isolated spikes (running median) and low-passed (:data:`CUTOFF`, zero phase:
the quasi-static body response), then compared
with what the rigid-body equilibrium and the kinematics require:

- suspension travel against the specific force (partial correlations, each
  regressor's effect with the others held; the aerodynamic lift
  :math:`\tfrac12 \rho A c_L v_x^2`, which the accelerometer does not sense,
  is held too where that decides, :func:`load_regressors`): a left turn (:math:`a_y > 0`)
  compresses the right wheels, braking (:math:`a_x < 0`) the front ones, a
  larger :math:`a_z` all four (the signs follow from :func:`travel_response`,
  the equilibrium of :mod:`wheelload.models.equilibrium` on the suspension's
  stiffness, and are pinned by a test against the plant);
- :math:`\dot v_x = a_x` on level ground (its ratio names vx in km/h or mph,
  ax in g) and :math:`v_x \omega_z = a_y` in steady cornering (ay in g, vx in
  km/h, wz in deg/s), when the log has the yaw rate;
- without the yaw rate, a left-right travel difference above
  :data:`MAX_ROLL_TRAVEL` per m/s^2 of ay (a roll gradient beyond any road car)
  names ay in g.

A wrong sign is explained by the wiring mistakes that predict exactly the
observed pattern (travel sign, one wheel's sign, left/right or front/rear
swapped, ay or ax sign). A check with too little excitation (a straight
line, a log at rest) cannot decide and is reported as such, never as a
failure. Duplicate column names are an error.

Example
-------
>>> report = check_wiring(signals.t, signals.vx, signals.acc, signals.d, signals.rates)
>>> report.failures
()
"""

from __future__ import annotations

import enum
import functools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.kernels import order_statistics, zero_phase
from wheelload.estimators.logs.latency import Lag, channel_lags
from wheelload.estimators.logs.own_clocks import on_imu_clock
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.conventions import WHEELS
from wheelload.models.inputs import TRAVEL, input_index
from wheelload.models.runtime.function_cache import Builder
from wheelload.models.runtime.function_library import compiled_function

#: The model Functions the checks evaluate, by name (imported where they are built; a warm
#: run reads them as compiled C: ``models/runtime/function_library.py``).
GATES_FUNCTION = Builder("wheelload.models.terms", "gates_function")
SUSPENSION_FUNCTION = Builder("wheelload.models.suspension.pseudo_measurement",
                              "suspension_function")  # fmt: skip
EQUILIBRIUM_FUNCTION = Builder("wheelload.models.equilibrium", "equilibrium_function")
RESPONSE_FUNCTION = Builder("wheelload.estimators.logs.checks", "response_jacobians_function")
WINDOW = 120.0  # s of motion examined, from the first sample with |vx| > MOVING
MOVING = 2.0  # m/s
CUTOFF = 1.0  # Hz, quasi-static body response
RATE = 10.0  # Hz, after low-pass and decimation
MEDIAN_WINDOW = 3  # samples: a running median first removes isolated spikes
MIN_STD = {"ax": 0.5, "ay": 0.5, "az": 0.15}  # m/s^2 low-passed, to decide
SIGN_THRESHOLD = 0.3  # |partial correlation| below which a sign is not decided
SIGNIFICANCE = 2.5  # standard errors a partial correlation must reach on a short log
KINEMATIC_CORRELATION = 0.8  # |correlation| needed to take a kinematic ratio
MAX_ROLL_TRAVEL = 0.03  # m per m/s^2: 11 deg/g of roll on a 1.5 m track
MIN_ROLL_TRAVEL = 0.002  # m, std of the left-right travel difference needed to decide
UNIT_TOLERANCE = 0.25  # relative distance (in log) to a known unit factor
#: Travel-response signs per wheel (FL, FR, RL, RR) to ax, ay, az (see travel_response).
EXPECTED_SIGNS = {
    "ax": (-1, -1, +1, +1),
    "ay": (-1, +1, -1, +1),
    "az": (+1, +1, +1, +1),
}
#: Known unit mistakes: factor by which the ratio exceeds 1 (see _unit_of).
UNIT_FACTORS = {"mph": 2.23694, "km/h": 3.6, "g": 1.0 / 0.101972, "deg/s": 57.2958}


class Outcome(enum.Enum):
    PASSED = "passed"
    FAILED = "failed"
    UNDECIDED = "could not decide"


@dataclass(frozen=True, kw_only=True)
class Check:
    """One statistic of the log against the physics, and its outcome."""

    name: str
    statistic: float
    outcome: Outcome
    note: str


@dataclass(frozen=True, kw_only=True)
class CheckReport:
    """Checks of a log and their outcomes (the wiring and the plausibility reports)."""

    checks: tuple[Check, ...]

    @property
    def failures(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if c.outcome is Outcome.FAILED)

    @property
    def undecided(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if c.outcome is Outcome.UNDECIDED)

    def statistic(self, name: str) -> float:
        """The statistic of the check called ``name``."""
        (check,) = [c for c in self.checks if c.name == name]
        return check.statistic


@dataclass(frozen=True, kw_only=True)
class WiringReport(CheckReport):
    """All checks and, if any failed, the explanation of the mistake."""

    diagnosis: str


class WiringError(ValueError):
    """A log whose channels contradict the physics: names the channel and the mistake."""


def duplicate_columns(names: Sequence[str]) -> str | None:
    """The first column named twice, or None; pandas' renamed copies ``x.1`` count too.

    ``pandas.read_csv`` renames a repeated ``x`` to ``x.1``, ``x.2``; such a
    name is taken as a duplicate when ``x`` is also a column.
    """
    names = [str(name).strip() for name in names]
    seen = set()
    for name in names:
        if name in seen:
            return name
        seen.add(name)
    for name in names:
        match = re.fullmatch(r"(.+)\.(\d+)", name)
        if match and match.group(1) in seen:
            return match.group(1)
    return None


def travel_response(vehicle: Vehicle) -> np.ndarray:
    r"""Quasi-static travel per unit specific force, (4 wheels) x (ax, ay, az), in m/(m/s^2).

    The pseudo-measured loads :math:`z(d, a)` (the vehicle's model terms: the
    links carry :math:`L = \partial z/\partial a` past the springs) must
    satisfy the equilibrium :math:`A z = b(d, a)`; linearised at rest
    (:math:`a = (0, 0, g)`), :math:`(A K - \partial b/\partial d)\,\Delta d =
    (\partial b/\partial a - A L)\,\Delta a` with :math:`K = \partial z /
    \partial d`; with a rigid body (no warp, :math:`d_{FL} - d_{FR} - d_{RL} +
    d_{RR} = 0`) that fixes :math:`\Delta d`.
    """
    p = ModelParameters.from_vehicle(vehicle).vector()
    gates = compiled_function(GATES_FUNCTION)(np.ones(len(INPUTS)), p)[0].ravel()
    travel, acc = input_index(TRAVEL), input_index(("ax", "ay", "az"))
    rest = np.zeros(len(INPUTS))
    rest[INPUTS.index("az")] = GRAVITY
    rest[list(input_index(("az_fl", "az_fr", "az_rl", "az_rr")))] = GRAVITY
    A, Z, Bu = compiled_function(RESPONSE_FUNCTION)(rest, gates, p)
    K, L = Z[:, travel], Z[:, acc]
    system = np.vstack([A @ K - Bu[:, travel], [1.0, -1.0, -1.0, 1.0]])
    return np.linalg.solve(system, np.vstack([Bu[:, acc] - A @ L, np.zeros((1, 3))]))


def response_jacobians_function() -> ca.Function:
    """``travel_response_jacobians(u, gates, p) -> (A, dz/du, db/du)``: the equilibrium
    matrix and the Jacobians of the pseudo-measured loads ``z`` and of ``b`` (eq. 15-16)."""
    from wheelload.models import GATES, equilibrium_function, suspension_function

    u = ca.SX.sym("u", len(INPUTS))
    gates = ca.SX.sym("gates", len(GATES))
    p = ca.SX.sym("p", len(ModelParameters.names()))
    z = suspension_function()(u, gates, p)
    A, b = equilibrium_function()(u, gates, p)
    return ca.Function("travel_response_jacobians", [u, gates, p],
                       [A, ca.jacobian(z, u), ca.jacobian(b, u)], ["u", "gates", "p"],
                       ["A", "dz_du", "db_du"])  # fmt: skip


#: Hz, the lowest mean rate of a channel's samples that the :data:`CUTOFF` low-pass can use:
#: a channel at a lower logging rate (NaN where it has no new value) is interpolated
#: between its samples; a sparser one is left out of the checks (could not decide).
MIN_CHANNEL_RATE = 4.0 * CUTOFF


def _fill(values: np.ndarray, duration: float) -> np.ndarray | None:
    """Interpolate missing samples between the channel's own (a channel at a lower rate,
    or with dropouts); None if it has fewer than :data:`MIN_CHANNEL_RATE` samples per second
    over ``duration`` [s] (or fewer than two)."""
    good = np.isfinite(values)
    count = int(good.sum())
    if count < 2 or count < MIN_CHANNEL_RATE * duration:
        return None
    index = np.arange(values.size)
    return np.interp(index, index[good], values[good])


def quasi_static(t: np.ndarray, channels: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Low-passed, decimated channels over the examined window (missing channels dropped)."""
    fs = 1.0 / float(order_statistics.median(np.diff(t)))
    b, a = zero_phase.butter2(min(CUTOFF / (0.5 * fs), 0.9))
    step = max(int(fs / RATE), 1)
    result = {}
    duration = float(t[-1] - t[0])
    for name, values in channels.items():
        values = np.asarray(values, float)
        low = _low_passed(values.tobytes(), tuple(b), tuple(a), step, duration)
        if low is not None:
            result[name] = low
    result["t"] = t[::step]
    return result


@functools.lru_cache(maxsize=32)
def _low_passed(values: bytes, b: tuple, a: tuple, step: int, duration: float) -> np.ndarray | None:
    """One channel of :func:`quasi_static` (``values``: its float64 bytes), read-only, or
    None; kept, as the wiring and plausibility checks examine the same window."""
    filled = _fill(np.frombuffer(values), duration)
    if filled is None or filled.size <= 3 * max(len(a), len(b)):
        return None
    despiked = zero_phase.medfilt(filled, MEDIAN_WINDOW)  # single-sample outliers
    low = zero_phase.filtfilt(np.array(b), np.array(a), despiked)[::step]
    low.flags.writeable = False
    return low


def _decisive_correlation(t: np.ndarray) -> float:
    r"""Smallest :math:`|r|` taken as a decided sign: :data:`SIGN_THRESHOLD`, or more on a
    short log, :math:`2.5/\sqrt{n - 3}` with :math:`n = 2 f_c T` independent samples of
    the :data:`CUTOFF` low-passed channels over :math:`T` seconds (a 4 s log decides nothing
    on chance correlations)."""
    independent = 2.0 * CUTOFF * float(t[-1] - t[0]) - 3.0
    return max(SIGN_THRESHOLD, SIGNIFICANCE / math.sqrt(max(independent, 1.0)))


def load_regressors(q: dict[str, np.ndarray]) -> tuple[list[str], np.ndarray]:
    r"""The quasi-static loads the travel answers to: the logged specific-force axes, then
    :math:`v_x^2` (the aerodynamic lift :math:`\tfrac12 \rho A c_L v_x^2` compresses the
    springs unseen by the accelerometer; in stop-and-go it follows the speed, which is
    correlated with :math:`a_x`), left out at a constant speed. Returns the axes' names and
    the columns (axes first, then :math:`v_x^2`)."""
    axes = [axis for axis in MIN_STD if axis in q]
    columns = [q[axis] for axis in axes]
    if "vx" in q:
        lift = q["vx"] ** 2
        if np.ptp(lift) > 1e-9 * max(float(np.max(lift)), 1.0):
            columns.append(lift)
    return axes, np.column_stack(columns) if columns else np.empty((q["t"].size, 0))


def _partial_correlations(y: np.ndarray, regressors: np.ndarray) -> np.ndarray:
    """Partial correlation of ``y`` with each column of ``regressors`` given the others."""
    X = np.column_stack([np.ones(y.size), regressors])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    residual = y - X @ coef
    dof = max(y.size - X.shape[1], 1)
    sigma2 = residual @ residual / dof
    covariance = sigma2 * np.linalg.pinv(X.T @ X)
    t = coef[1:] / np.sqrt(np.maximum(np.diag(covariance)[1:], 1e-300))
    return t / np.sqrt(t**2 + dof)


def _sign(value: float) -> int:
    return 0 if abs(value) < SIGN_THRESHOLD or not math.isfinite(value) else int(np.sign(value))


def _unit_of(ratio: float) -> str | None:
    """'ok', the nearest unit of :data:`UNIT_FACTORS` within the tolerance, or None."""
    if not ratio > 0.0:
        return None
    distance = {unit: abs(math.log(ratio / factor))
                for unit, factor in {"ok": 1.0, **UNIT_FACTORS}.items()}  # fmt: skip
    unit = min(distance, key=distance.__getitem__)
    return unit if distance[unit] < UNIT_TOLERANCE else None


@dataclass(frozen=True)
class _Hypothesis:
    """A wiring mistake and the signs it predicts."""

    explanation: str
    wheel_signs: dict[str, tuple[int, int, int, int]]  # per axis, predicted agreement
    lateral: int = +1  # sign of vx wz against ay
    longitudinal: int = +1  # sign of dvx/dt against ax


def _hypotheses() -> list[_Hypothesis]:
    plus = (1, 1, 1, 1)
    minus = (-1, -1, -1, -1)
    found = [
        _Hypothesis(
            "the travel columns d_fl d_fr d_rl d_rr have the wrong sign (extension "
            "positive): give compression positive",
            {"ax": minus, "ay": minus, "az": minus},
        ),
        _Hypothesis(
            "column 'ay' has the wrong sign: give ay positive to the left (ISO 8855: a left "
            "turn gives ay > 0)",
            {"ax": plus, "ay": minus, "az": plus},
            lateral=-1,
        ),
        _Hypothesis(
            "left and right travel columns look swapped (d_fl with d_fr, d_rl with d_rr)",
            {"ax": plus, "ay": minus, "az": plus},
        ),
        _Hypothesis(
            "column 'ax' has the wrong sign: give ax positive forward",
            {"ax": minus, "ay": plus, "az": plus},
            longitudinal=-1,
        ),
        _Hypothesis(
            "front and rear travel columns look swapped (d_fl with d_rl, d_fr with d_rr)",
            {"ax": minus, "ay": plus, "az": plus},
        ),
    ]
    for axle, (left, right) in (("front", (0, 1)), ("rear", (2, 3))):
        signs = tuple(-1 if k in (left, right) else 1 for k in range(4))
        found.append(
            _Hypothesis(
                f"columns 'd_{WHEELS[left]}' and 'd_{WHEELS[right]}' look swapped "
                f"(left and right of the {axle} axle)",
                {"ax": plus, "ay": signs, "az": plus},  # type: ignore[dict-item]
            )
        )
    for k, wheel in enumerate(WHEELS):
        signs = tuple(-1 if j == k else 1 for j in range(4))
        found.append(
            _Hypothesis(
                f"column 'd_{wheel}' has the wrong sign: give compression positive",
                {"ax": signs, "ay": signs, "az": signs},  # type: ignore[dict-item]
            )
        )
    return found


def _explain(observed: dict[str, list[int]], lateral: int, longitudinal: int) -> str:
    """The hypotheses that predict every decided sign, joined; or a plain listing."""

    def fits(h: _Hypothesis) -> bool:
        for axis, signs in observed.items():
            if any(s != 0 and s != e for s, e in zip(signs, h.wheel_signs[axis])):
                return False
        return (lateral == 0 or lateral == h.lateral) and (
            longitudinal == 0 or longitudinal == h.longitudinal
        )

    matches = [h.explanation for h in _hypotheses() if fits(h)]
    if matches:
        return "; or ".join(matches)
    wrong = [f"d_{w} against {axis}" for axis, s in observed.items()
             for w, v in zip(WHEELS, s) if v < 0]  # fmt: skip
    if lateral < 0:
        wrong.append("ay against vx wz")
    if longitudinal < 0:
        wrong.append("dvx/dt against ax")
    return "the physics contradicts " + ", ".join(wrong) + ": check the signs and wiring"


def check_wiring(
    t: np.ndarray,
    vx: np.ndarray,
    acc: np.ndarray,
    d: np.ndarray,
    rates: np.ndarray | None = None,
    *,
    own_clocks: bool = False,
) -> WiringReport:
    """Run every check on the first :data:`WINDOW` s of motion (see module docstring).

    ``own_clocks``: the channels are on their own clocks, NaN where one has no new value
    (``[clock] union``); the checks compare them on the IMU's own stamps (``ax``'s),
    each interpolated onto them (:func:`~wheelload.estimators.logs.own_clocks.on_imu_clock`).
    """
    if own_clocks:
        t, vx, acc, d, rates = on_imu_clock(t, acc, vx, acc, d, rates)
    window = motion_window(t, vx)
    if window is None:
        note = f"less than 4 s above {MOVING} m/s"
        return WiringReport(checks=(undecided_check("motion", note),), diagnosis="")
    channels = {"vx": vx, "ax": acc[:, 0], "ay": acc[:, 1], "az": acc[:, 2]}
    channels.update({f"d_{w}": d[:, k] for k, w in enumerate(WHEELS)})
    if rates is not None:
        channels["wz"] = rates[:, 2]
    q = quasi_static(t[window], {name: values[window] for name, values in channels.items()})
    travel, observed = _travel_checks(q)
    kinematic, signs, ratios = _kinematic_checks(q)
    roll, roll_mistakes = _roll_gain(q)
    mistakes = []
    if any(s < 0 for s in [*sum(observed.values(), []), *signs.values()]):
        mistakes.append(_explain(observed, signs["lateral"], signs["longitudinal"]))
    mistakes += _unit_mistakes(ratios) + roll_mistakes
    lags = _lag_checks(channel_lags(t[window], vx[window], acc[window], d[window],
                                    None if rates is None else rates[window]))  # fmt: skip
    return WiringReport(checks=(*travel, *kinematic, *roll, *lags),
                        diagnosis="; and ".join(mistakes))  # fmt: skip


def _lag_checks(lags: list[Lag]) -> list[Check]:
    """A check per channel lag (``latency.py``): passed when no lag, failed (a note, not a
    refusal) with the channel map's fix when the channel lags, else undecided."""
    checks = []
    for lag in lags:
        name = f"{lag.channel} lag against {lag.against}"
        if not lag.decided:
            checks.append(undecided_check(name, lag.note, lag.lag))
            continue
        key = "d_*" if lag.channel.startswith("d ") else lag.channel
        found = f"{lag.lag:+.3f} s +- {lag.std:.3f} s (r {abs(lag.correlation):.2f})"
        note = f"{lag.channel} lags {lag.against} by {found}" + (
            f": add {lag.lag:.3f} to channels.{key}.latency" if lag.lag > 0 else ""
        )
        outcome = Outcome.FAILED if lag.significant else Outcome.PASSED
        checks.append(Check(name=name, statistic=lag.lag, outcome=outcome, note=note))
    return checks


def motion_window(t: np.ndarray, vx: np.ndarray) -> slice | None:
    """The first :data:`WINDOW` s from the first sample above :data:`MOVING`, or None."""
    moving = np.flatnonzero(np.abs(np.nan_to_num(vx)) > MOVING)
    if moving.size == 0:
        return None
    start = int(moving[0])
    stop = int(np.searchsorted(t, t[start] + WINDOW))
    return slice(start, stop) if t[stop - 1] - t[start] >= 4.0 else None


def undecided_check(name: str, note: str, statistic: float = math.nan) -> Check:
    """A check that could not decide, and why (``note``)."""
    return Check(name=name, statistic=statistic, outcome=Outcome.UNDECIDED, note=note)


def _travel_checks(q: dict[str, np.ndarray]) -> tuple[list[Check], dict[str, list[int]]]:
    """Per wheel and axis: agreement = expected sign x partial correlation; observed signs.

    The partial correlation with the lift's :math:`v_x^2` held (:func:`load_regressors`)
    where it decides; else the one with the specific force alone (a log whose speed follows
    ``ax`` leaves the two inseparable, and a car without downforce has no lift to hold)."""
    checks = []
    observed = {axis: [0, 0, 0, 0] for axis in MIN_STD}
    axes, regressors = load_regressors(q)
    if not axes:
        return checks, observed
    threshold = _decisive_correlation(q["t"])
    for k, wheel in enumerate(WHEELS):
        name = f"d_{wheel}"
        if name not in q:
            continue
        held = _partial_correlations(q[name], regressors)
        alone = _partial_correlations(q[name], regressors[:, : len(axes)])
        for j, axis in enumerate(axes):
            lift_held = abs(held[j]) >= threshold and regressors.shape[1] > len(axes)
            agreement = float(EXPECTED_SIGNS[axis][k] * (held[j] if lift_held else alone[j]))
            check = f"{name} against {axis}"
            if not np.std(q[axis]) > MIN_STD[axis]:
                checks.append(undecided_check(check, f"{axis} varies too little", agreement))
                continue
            observed[axis][k] = _sign(agreement) if abs(agreement) >= threshold else 0
            if observed[axis][k] == 0:
                checks.append(
                    undecided_check(check, f"correlation below {threshold:.2f}", agreement)
                )
                continue
            note = "partial correlation times the expected sign" + (
                " (vx^2 held)" if lift_held else ""
            )
            outcome = Outcome.FAILED if observed[axis][k] < 0 else Outcome.PASSED
            checks.append(Check(name=check, statistic=agreement, outcome=outcome, note=note))
    return checks, observed


def _kinematic_checks(
    q: dict[str, np.ndarray],
) -> tuple[list[Check], dict[str, int], dict[str, float]]:
    """dvx/dt = ax and vx wz = ay: checks, signs (0 undecided) and ratios (decided only)."""
    checks, signs, ratios = [], {"longitudinal": 0, "lateral": 0}, {}
    relations = {"longitudinal": ("dvx/dt against ax", "ax"),
                 "lateral": ("vx wz against ay", "ay")}  # fmt: skip
    for key, (name, axis) in relations.items():
        needed = ("vx", "wz", axis) if key == "lateral" else ("vx", axis)
        missing = [c for c in needed if c not in q]
        if missing:
            checks.append(undecided_check(name, f"no {missing[0]} in the log"))
            continue
        y = np.gradient(q["vx"], q["t"]) if key == "longitudinal" else q["vx"] * q["wz"]
        if not max(np.std(y), np.std(q[axis])) > MIN_STD[axis]:
            checks.append(undecided_check(name, f"{axis} varies too little"))
            continue
        correlation = float(np.corrcoef(y, q[axis])[0, 1])
        if not abs(correlation) >= KINEMATIC_CORRELATION:
            note = "correlation too weak (grade, bank or slip)"
            checks.append(undecided_check(name, note, correlation))
            continue
        signs[key] = int(np.sign(correlation))
        ratios[key] = float(np.std(y) / np.std(q[axis]))
        right = signs[key] > 0 and _unit_of(ratios[key]) == "ok"
        checks.append(Check(name=name, statistic=signs[key] * ratios[key],
                            outcome=Outcome.PASSED if right else Outcome.FAILED,
                            note="signed ratio std(left) / std(right), 1 expected"))  # fmt: skip
    return checks, signs, ratios


def _roll_gain(q: dict[str, np.ndarray]) -> tuple[list[Check], list[str]]:
    """Without a yaw rate: ay in g if the roll travel per unit ay exceeds MAX_ROLL_TRAVEL."""
    name = "roll travel per ay"
    if "wz" in q or not all(f"d_{w}" in q for w in WHEELS):
        return [], []
    roll = 0.5 * (q["d_fr"] + q["d_rr"] - q["d_fl"] - q["d_rl"])
    correlation = float(np.corrcoef(roll, q["ay"])[0, 1])
    if not (np.std(roll) > MIN_ROLL_TRAVEL and abs(correlation) > KINEMATIC_CORRELATION):
        return [undecided_check(name, "too little roll")], []
    gain = float(np.std(roll) / np.std(q["ay"]))
    failed = gain > MAX_ROLL_TRAVEL
    check = Check(name=name, statistic=gain, outcome=Outcome.FAILED if failed else Outcome.PASSED,
                  note="m of left-right travel difference per m/s^2")  # fmt: skip
    if not failed:
        return [check], []
    return [check], [
        f"column 'ay' looks like g (the left-right travel difference grows by "
        f"{1000 * gain:.0f} mm per unit of ay, more than {1000 * MAX_ROLL_TRAVEL:.0f}"
        " mm per m/s^2 of any road car): give m/s^2"
    ]


def _unit_mistakes(ratios: dict[str, float]) -> list[str]:
    """Unit mistakes named by the kinematic ratios (see module docstring)."""
    units = {key: _unit_of(ratio) for key, ratio in ratios.items()}
    lon, lat = units.get("longitudinal"), units.get("lateral")
    measured = {"longitudinal": "dvx/dt : ax", "lateral": "vx wz : ay"}
    found = []
    speed = [key for key, unit in units.items() if unit in ("km/h", "mph")]
    if speed and not (lon == "ok" and lat in ("km/h", "mph")):
        unit = units[speed[0]]
        shown = ", ".join(f"{measured[key]} = {ratios[key]:.3g}" for key in speed)
        found.append(
            f"column 'vx' looks like {unit} ({shown}): give m/s (from wheel speeds: check "
            "their 'radius' and 'ratio', shaft turns per wheel turn)"
        )
    elif speed:
        found.append(f"vx wz is {ratios['lateral']:.3g} x ay while dvx/dt matches ax: "
                     "check the units of ay and wz")  # fmt: skip
    for key, unit, column in (("longitudinal", "g", "ax"), ("lateral", "g", "ay"),
                              ("lateral", "deg/s", "wz")):  # fmt: skip
        if units.get(key) == unit:
            fix = "rad/s" if unit == "deg/s" else "m/s^2"
            found.append(f"column '{column}' looks like {unit} ({measured[key]} = "
                         f"{ratios[key]:.3g}): give {fix}")  # fmt: skip
    for key, unit in units.items():
        if unit is None:
            found.append(f"{measured[key]} = {ratios[key]:.3g}, not 1: check the units of "
                         "vx, ax, ay and wz")  # fmt: skip
    return found


def describe(report: CheckReport, title: str = "wiring checks") -> str:
    """One line: how many checks passed, and which could not decide (and why).

    ``report``: any report with ``checks`` and ``undecided`` (also the plausibility
    report of :mod:`~wheelload.estimators.logs.plausibility`, with its ``title``).
    """
    passed = sum(c.outcome is Outcome.PASSED for c in report.checks)
    lags = [c.note for c in report.failures if " lag against " in c.name]
    return (
        f"{title}: {passed} passed"
        + (f"; could not decide: {_undecided_names(report)}" if report.undecided else "")
        + "".join(f"; {note}" for note in lags)
    )


def _undecided_names(report: WiringReport) -> str:
    """The undecided checks grouped by reason, the four wheels of one axis as ``d_*``."""
    groups: dict[str, list[str]] = {}
    for check in report.undecided:
        name = re.sub(r"^d_(fl|fr|rl|rr) ", "d_* ", check.name)
        names = groups.setdefault(check.note, [])
        if name not in names:
            names.append(name)
    return "; ".join(f"{', '.join(names)} ({note})" for note, names in groups.items())


def raise_for_wiring(report: WiringReport, source: str) -> None:
    """One-line :class:`WiringError` naming the channel and the likely mistake, if any."""
    if not report.diagnosis:
        return
    raise WiringError(
        f"{source}: wiring check: {report.diagnosis}"
        + (f" (could not decide: {_undecided_names(report)})" if report.undecided else "")
        + "; if the log is right, give --skip-wiring-checks"
    )
