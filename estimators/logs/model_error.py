r"""The model-error channel: which vehicle-file parameter a log's residuals point at.

Beside the sensor-fault channel (:mod:`.fault_monitor`, a bias of one sensor) this asks,
once per log, whether the equilibrium residual at the pseudo-measured loads,
:math:`r_t = b(u_t; p) - A(p)\,z(u_t; p)` (every model term the inputs allow, as the
parity test), is explained by one parameter of the vehicle file being wrong: each
hypothesis :math:`k` changes the file by a unit step (springs, anti-roll bars, one axle's
rates together as a forgotten motion ratio, mass, CG height; :data:`HYPOTHESES`), whose signature
:math:`s_{k,t} = (\partial r_t / \partial p)\,\Delta p_k` comes from the models' Jacobians.
With a constant per row (what a payload, a sensor bias or a travel zero leaves: the online
payload and the travel-zero check take those), weighted least squares

.. math:: \min_{c, \delta_k} \sum_t \lVert W^{1/2} (r_t + s_{k,t} \delta_k - c) \rVert^2,
   \quad W = \mathrm{diag}(1 / r_c)

gives the size :math:`\delta_k` and the share of the residual's variation it explains,
:math:`e_k = 1 - E_k / E_0`. The best hypothesis is named when it explains at least
:data:`EXPLAINED` of it, moves the residual by more than the model's own scatter
(:data:`SIGNIFICANT` times the residual's spread without it) and fits a car (no negative
stiffness or mass, within 2 times the file's value, 4 for a motion ratio; samples a guard
doubted are left out). A gain the file has wrong
grows with the excitation; a sensor bias does not (that is the fault monitor's).

A corner's travel zero (a potentiometer not zeroed) is told by the travel *warp*:
for a rigid body :math:`w = (d_{fl} - d_{fr}) / t_f - (d_{rl} - d_{rr}) / t_r = 0`, so
its mean while the car is quiet (:math:`|a_y|` below 1 m/s²) is the sum of the
corners' zero errors; the corner is the one whose offset best explains the mean
equilibrium residual there, and its size is :math:`\bar w` times its track
(:func:`zero_offset`).

Example
-------
>>> finding = diagnose(signals, vehicle)
>>> print(finding.message() if finding else "the file explains the log")
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.result import ModelError
from wheelload.estimators.types import Signals
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.conventions import WHEELS
from wheelload.models.inputs import SPECIFIC_FORCE, TRAVEL, input_index
from wheelload.models.loaded_vehicle import payload_of
from wheelload.models.runtime.function_cache import Builder
from wheelload.models.runtime.function_library import compiled_function

#: Share of the residual's variation the best hypothesis must explain to be named (the
#: bundled cars' exact files: at most 0.40 on 20 scenario logs; a file 20 % off: 0.58-0.96).
EXPLAINED = 0.5
#: Its fitted change of the residual must exceed this many times the residual's spread
#: that it leaves (RMS over the log, weighted rows), or it is the model's own scatter.
SIGNIFICANT = 0.5
#: A hypothesis of another family explaining this share of the best's is named beside it
#: (mass and CG height both scale the load transfer m h a).
RIVAL = 0.95
#: A motion ratio must leave at most this share of the residual energy the best other
#: hypothesis leaves (the bundled cars' plant logs: a front motion ratio of 0.7 forgotten
#: 0.11-0.69 on every log with motion; every other wrong file 0.91 or more).
MOTION_RATIO_MARGIN = 0.8
#: Lateral acceleration magnitude below which the car is quiet (travel warp and offsets
#: are read there) [m/s^2].
QUIET_ACCELERATION = 1.0
#: Smallest travel-zero error named [m]: the bundled cars' clean logs show up to 0.9 mm
#: of warp at a corner from the travel sensors' own linearity.
TRAVEL_ZERO_LIMIT = 1.5e-3
#: The quiet samples' two halves must agree on the travel warp to this share of it.
CONSISTENT = 0.5
#: At most this many samples are fitted (a long log is thinned evenly: 5000 samples of a
#: lap still hold every corner of it, at a fifth of a second apart).
MAX_SAMPLES = 5000


def _axles(vehicle: Vehicle, axles, **changes) -> Vehicle:
    suspension = vehicle.suspension
    for axle in axles:
        current = getattr(suspension, axle)
        new = {key: change(getattr(current, key)) for key, change in changes.items()}
        suspension = dataclasses.replace(suspension, **{axle: dataclasses.replace(current, **new)})
    return dataclasses.replace(vehicle, suspension=suspension)


def _mass(vehicle: Vehicle, step: float) -> Vehicle:
    mass = vehicle.mass
    added = step * mass.sprung
    return dataclasses.replace(
        vehicle,
        mass=dataclasses.replace(mass, sprung=mass.sprung + added, total=mass.total + added),
    )


@dataclass(frozen=True, kw_only=True)
class Hypothesis:
    """One way the vehicle file may be wrong: a unit step of some of its keys."""

    name: str  # what the message calls it
    family: str  # hypotheses of one family (the bars, one or both) are no rivals
    keys: tuple[str, ...]  # the file keys it changes
    unit: str  # unit of the values reported
    step: Callable[[Vehicle], Vehicle]  # the file with a unit step
    value: Callable[[Vehicle], tuple[float, ...]]  # the keys' values in the file
    factor: float = 2.0  # a fitted value this factor from the file's (either way) is no car's


def _relative(family, axles, key, unit, label):
    return Hypothesis(
        name=label,
        family=family,
        keys=tuple(f"suspension.{axle}.{key}" for axle in axles),
        unit=unit,
        step=lambda v: _axles(v, axles, **{key: lambda x: x * 1.01}),
        value=lambda v: tuple(getattr(getattr(v.suspension, axle), key) for axle in axles),
    )


def _bars(axles, label):
    # Absolute (a file without bars has none to scale): +1000 N/m per axle.
    return Hypothesis(
        name=label,
        family="bars",
        keys=tuple(f"suspension.{axle}.arb_rate" for axle in axles),
        unit="N/m",
        step=lambda v: _axles(v, axles, arb_rate=lambda x: x + 1000.0),
        value=lambda v: tuple(getattr(v.suspension, axle).arb_rate for axle in axles),
    )


#: An axle's rates a motion ratio scales (the rates at the wheel are the damper's times the
#: ratio squared); the stops are left out (their gaps are read at the wheel).
AXLE_RATES = ("spring_rate", "damper_push", "damper_pull", "arb_rate")
#: Smallest motion ratio a suspension has (double wishbones 0.5-1): its rates may then be
#: up to 1 / 0.5^2 = 4 times those at the wheel.
SMALLEST_MOTION_RATIO = 0.5


def _motion_ratio(axle: str):
    # All of one axle's rates by one factor: the file gives them at the damper (or the
    # spring), not at the wheel. The value reported is the spring rate.
    return Hypothesis(
        factor=1.0 / SMALLEST_MOTION_RATIO**2,
        name=f"{axle} motion ratio",
        family="motion ratio",
        keys=tuple(f"suspension.{axle}.{key}" for key in AXLE_RATES),
        unit="N/m",
        step=lambda v: _axles(v, (axle,), **{key: lambda x: x * 1.01 for key in AXLE_RATES}),
        value=lambda v: (getattr(v.suspension, axle).spring_rate,),
    )


BOTH, FRONT, REAR = ("front", "rear"), ("front",), ("rear",)
#: The file parameters a log's residual is tested against.
HYPOTHESES: tuple[Hypothesis, ...] = (
    _relative("springs", BOTH, "spring_rate", "N/m", "springs"),
    _relative("springs", FRONT, "spring_rate", "N/m", "front springs"),
    _relative("springs", REAR, "spring_rate", "N/m", "rear springs"),
    _bars(BOTH, "anti-roll bars"),
    _bars(FRONT, "front anti-roll bar"),
    _bars(REAR, "rear anti-roll bar"),
    _motion_ratio("front"),
    _motion_ratio("rear"),
    Hypothesis(
        name="mass",
        family="mass",
        keys=("mass.sprung", "mass.total"),
        unit="kg",
        step=lambda v: _mass(v, 0.01),
        value=lambda v: (v.mass.total,),
    ),
    Hypothesis(
        name="CG height",
        family="CG height",
        keys=("geometry.cg_height",),
        unit="m",
        step=lambda v: dataclasses.replace(
            v, geometry=dataclasses.replace(v.geometry, cg_height=v.geometry.cg_height + 0.01)
        ),
        value=lambda v: (v.geometry.cg_height,),
    ),
)


def _parity_rows(K: int):
    """The symbols ``(u, valid, p, dp)`` and the parity model's ``(z, A, b, T)`` on them."""
    import casadi as ca

    from wheelload.models import equilibrium_function, suspension_function  # symbolic
    from wheelload.models.terms import parity_model

    u = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("valid", len(INPUTS))
    p = ca.SX.sym("p", len(ModelParameters.names()))
    dp = ca.SX.sym("dp", p.shape[0], K)
    z, A, b, signatures = parity_model(suspension_function(), equilibrium_function(), u, valid, p)
    return (u, valid, p, dp), (z, A, b, signatures[:, :4])


def model_error_function():
    """``(u, valid, p, dp[np x K]) -> (r[3], S[3 x K], T[3 x 4])``: the parity residual
    :math:`r = b - A z`, its change along each file step and per metre of each corner's
    travel."""
    import casadi as ca

    inputs, (z, A, b, T) = _parity_rows(len(HYPOTHESES))
    p, dp = inputs[2], inputs[3]
    r = b - ca.mtimes(A, z)
    outputs = [r, ca.mtimes(ca.jacobian(r, p), dp), T]
    return ca.Function("model_error_rows", list(inputs), outputs,
                       ["u", "valid", "p", "dp"], ["r", "S", "T"])  # fmt: skip


def load_change_function():
    """``(u, valid, p, dp[np x 2]) -> (Z[4 x 2], B[3 x 2], A)``: the changes of :math:`z` and
    :math:`b` along a finding's step and its rival's, and :math:`A` (only built for a
    finding)."""
    import casadi as ca

    inputs, (z, A, b, _) = _parity_rows(2)
    p, dp = inputs[2], inputs[3]
    outputs = [ca.mtimes(ca.jacobian(z, p), dp), ca.mtimes(ca.jacobian(b, p), dp), A]
    return ca.Function("model_error_load_change", list(inputs), outputs,
                       ["u", "valid", "p", "dp"], ["Z", "B", "A"])  # fmt: skip


MODEL_ERROR_FUNCTION = Builder("wheelload.estimators.logs.model_error", "model_error_function")
LOAD_CHANGE_FUNCTION = Builder("wheelload.estimators.logs.model_error", "load_change_function")
LOADED_PARAMETERS = Builder("wheelload.models.loaded_vehicle", "loaded_parameters_function")


def _weighted_fit(r, S, weight):
    r"""The step :math:`\delta` that best cancels ``r`` (n x 3) with ``S`` (n x 3) about
    per-row constants, :math:`r + S \delta \approx c`; the residual energy left, and the
    energy with the constants alone."""
    r = (r - r.mean(axis=0)) * weight
    S = (S - S.mean(axis=0)) * weight
    base = float(np.sum(r * r))
    norm = float(np.sum(S * S))
    if norm <= 0.0 or base <= 0.0:
        return 0.0, base, base
    size = -float(np.sum(S * r)) / norm
    left = float(np.sum((r + size * S) ** 2))
    return size, left, base


@dataclass(frozen=True, kw_only=True, eq=False)
class Diagnosis:
    """What :func:`diagnose` found: the finding (None: the file explains the log), the
    travel zero to take off each corner [m] (4,), and for a file parameter its fitted step
    in the parameter vector, with a rival's that fits almost as well (columns of
    ``change``), at the parameters ``p`` checked (the loaded car)."""

    finding: ModelError | None
    travel_zero: np.ndarray
    p: np.ndarray | None = None
    change: np.ndarray | None = None  # (len(p), 1 or 2)

    def corrected(self, signals: Signals) -> Signals:
        """``signals`` with the travel zero taken off (the same object when there is none)."""
        if not np.any(self.travel_zero):
            return signals
        return dataclasses.replace(signals, d=signals.d - self.travel_zero)

    def load_change(self, U: np.ndarray) -> np.ndarray:
        """The loads' change [N] (n, 4) the finding implies on the samples of ``U`` (inputs
        x n), the larger of its and its rival's: what the estimate's σ is widened by
        (zeros without a file parameter)."""
        if self.change is None:
            return np.zeros((U.shape[1], 4))
        change = np.zeros((self.change.shape[0], 2))
        change[:, : self.change.shape[1]] = self.change
        valid = np.isfinite(U).astype(float)
        dz, db, A = compiled_function(LOAD_CHANGE_FUNCTION).map(
            np.nan_to_num(U), valid, self.p, change
        )
        n = U.shape[1]
        rows = {name: out.reshape(out.shape[0], n, -1).transpose(1, 0, 2)
                for name, out in zip(("Z", "B", "A"), (dz, db, A), strict=True)}  # fmt: skip
        return np.max([_load_change(rows, k) for k in range(self.change.shape[1])], axis=0)


NOTHING = Diagnosis(finding=None, travel_zero=np.zeros(4))


def diagnose(signals: Signals, vehicle: Vehicle, **options) -> Diagnosis:
    """:func:`diagnose_inputs` on a whole log's :class:`Signals`."""
    return diagnose_inputs(
        input_matrix(signals, RateDerivativeFilter.of(vehicle)), vehicle, **options
    )


def diagnose_inputs(
    U: np.ndarray,
    vehicle: Vehicle,
    exclude: np.ndarray | None = None,
    *,
    travel_zero: bool = True,
    mass_properties: np.ndarray | None = None,
) -> Diagnosis:
    """The vehicle-file parameter or travel zero the log's residuals point at (module
    docstring) and its size, from the log's inputs ``U`` (inputs x n, possibly thinned).
    ``exclude`` (n,): samples left out (an isolated sensor fault's); ``travel_zero``
    False: the travel zeros are known (static loads measured at the log's rest), only
    the file is checked; ``mass_properties`` (``MASS_PROPERTIES``): the car as the online
    payload estimate found it, checked instead of the file's masses (a payload is no
    model error)."""
    usable = np.all(np.isfinite(U[_required()]), axis=0)
    if exclude is not None:
        usable &= ~np.asarray(exclude, bool)
    index = np.flatnonzero(usable)
    if index.size < 100:
        return NOTHING
    index = index[:: max(1, index.size // MAX_SAMPLES)]
    parameters, p, dp = _unit_steps(vehicle)
    rows = _rows(U[:, index], p, dp)
    # A residual beyond what the car's weight can make is a sample no guard caught (a spike
    # of 1e30): left out, as are the samples the guards doubted.
    kept = _physical(rows["r"], parameters)
    rows = {name: value[kept] for name, value in rows.items()}
    index = index[kept]
    if index.size < 100:
        return NOTHING
    # A zero is read against the file's car: the online payload takes up a zero's
    # equilibrium signature (its warp it cannot), which tells the corner.
    zero = zero_offset(U[:, index], rows["r"], rows["T"], vehicle) if travel_zero else None
    if zero is not None:
        offsets = np.zeros(4)
        offsets[TRAVEL.index(zero.keys[0])] = zero.fitted_value[0]
        return Diagnosis(finding=zero, travel_zero=offsets)
    if mass_properties is not None:
        payload = np.array(payload_of(parameters, mass_properties), float)
        p = compiled_function(LOADED_PARAMETERS)(p, payload)[0].ravel()
        rows = _rows(U[:, index], p, dp)
    r, S = rows["r"], rows["S"]
    weight = 1.0 / np.sqrt(np.asarray(vehicle.filter.constraint_noise_density, float))
    fits = [_weighted_fit(r, S[:, :, k], weight) for k in range(len(HYPOTHESES))]
    explained = np.array([1.0 - left / base if base > 0 else 0.0 for _, left, base in fits])
    explained[~_considered(fits)] = -np.inf
    order = np.argsort(-explained)
    best = int(order[0])
    size, left, base = fits[best]
    if explained[best] < EXPLAINED or np.sqrt(max(base - left, 0.0)) < SIGNIFICANT * np.sqrt(left):
        return NOTHING
    hypothesis = HYPOTHESES[best]
    file_value = hypothesis.value(vehicle)
    stepped = hypothesis.value(hypothesis.step(vehicle))
    fitted = tuple(v + size * (s - v) for v, s in zip(file_value, stepped, strict=True))
    if not _plausible(fitted, file_value, hypothesis.factor):
        return NOTHING  # a sensor the guards did not catch, not a car
    rivals = [k for k in order[1:] if HYPOTHESES[k].family != hypothesis.family]
    close = rivals and explained[rivals[0]] > RIVAL * explained[best]
    finding = ModelError(
        name=hypothesis.name,
        keys=hypothesis.keys,
        unit=hypothesis.unit,
        file_value=file_value,
        fitted_value=fitted,
        explained=float(explained[best]),
        runner_up=HYPOTHESES[rivals[0]].name if close else "",
    )
    steps = [best, *([rivals[0]] if close else [])]
    change = np.column_stack([dp[:, k] * fits[k][0] for k in steps])
    return Diagnosis(finding=finding, travel_zero=np.zeros(4), p=p, change=change)


def _considered(fits) -> np.ndarray:
    """The hypotheses (bool, :data:`HYPOTHESES` order) that may be named: a motion ratio, which
    moves four rates of an axle at once, only when it leaves at most :data:`MOTION_RATIO_MARGIN`
    of the residual energy the best other hypothesis leaves."""
    left = np.array([left for _, left, _ in fits])
    ratio = np.array([h.family == "motion ratio" for h in HYPOTHESES])
    return ~ratio | (
        left.min(where=ratio, initial=np.inf) <= MOTION_RATIO_MARGIN * left[~ratio].min()
    )


@functools.lru_cache(maxsize=8)
def _unit_steps(vehicle: Vehicle) -> tuple[ModelParameters, np.ndarray, np.ndarray]:
    """The file's parameters, their vector ``p`` and each hypothesis's unit step in it
    (columns of ``dp``): read-only, kept for the last few files (a study runs one file
    over many logs)."""
    parameters = ModelParameters.from_vehicle(vehicle)
    p = parameters.vector()
    dp = np.column_stack(
        [ModelParameters.from_vehicle(h.step(vehicle)).vector() - p for h in HYPOTHESES]
    )
    p.flags.writeable = dp.flags.writeable = False
    return parameters, p, dp


def _rows(U, p, dp) -> dict[str, np.ndarray]:
    """:func:`model_error_function` on the samples of ``U`` (inputs x n), compiled; each
    output sample-first: r (n, 3), S (n, 3, K), T (n, 3, 4)."""
    n = U.shape[1]
    valid = np.isfinite(U).astype(float)
    outputs = compiled_function(MODEL_ERROR_FUNCTION).map(np.nan_to_num(U), valid, p, dp)
    names = ("r", "S", "T")
    return {
        name: out.reshape(out.shape[0], n, -1).transpose(1, 0, 2).squeeze(-1)
        if name == "r"
        else out.reshape(out.shape[0], n, -1).transpose(1, 0, 2)
        for name, out in zip(names, outputs, strict=True)
    }


def _load_change(rows, k: int) -> np.ndarray:
    r"""The loads' change (n, 4) of step ``k`` (column ``k`` of ``Z``, ``B``): per wheel
    the larger of the pseudo-measurement's change :math:`\Delta z` and its projection onto
    the equilibrium's, :math:`\Delta z + A^+ (\Delta b - A \Delta z)`,
    :math:`A^+ = A^T (A A^T)^{-1}` (the filter's loads sit between the two)."""
    dz, db, A = rows["Z"][:, :, k], rows["B"][:, :, k], rows["A"]
    gap = db - np.einsum("nij,nj->ni", A, dz)
    gram = np.einsum("nij,nkj->nik", A, A)
    projected = dz + np.einsum("nji,nj->ni", A, np.linalg.solve(gram, gap[..., None])[..., 0])
    return np.maximum(np.abs(dz), np.abs(projected))


def _physical(r, parameters: ModelParameters) -> np.ndarray:
    """Samples (n,) whose residual rows are within the whole weight, and its moment over the
    wheelbase and track, times the filter's load limit (3)."""
    weight = parameters.mass * GRAVITY
    scale = (
        3.0
        * weight
        * np.array(
            [1.0, parameters.lf + parameters.lr, max(parameters.track_front, parameters.track_rear)]
        )
    )
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(r) & (np.abs(r) <= scale), axis=1)


def _plausible(fitted, file_value, factor: float) -> bool:
    """Whether a fit is a car's: no negative value, and within ``factor`` of a file value
    that is not 0 (a bar the file leaves out may be any stiffness)."""
    for new, old in zip(fitted, file_value, strict=True):
        if new < 0 or (old > 0 and not old / factor <= new <= old * factor):
            return False
    return True


def _required() -> list[int]:
    names = (*TRAVEL, *(f"v_{w}" for w in WHEELS), *SPECIFIC_FORCE, "vx")
    return [INPUTS.index(name) for name in names]


def zero_offset(u, r, T, vehicle: Vehicle) -> ModelError | None:
    r"""A corner's travel zero from the quiet samples' travel warp, or None.

    ``u`` inputs (len(INPUTS) x n), ``r`` the residual (n x 3), ``T`` its change per metre
    of each corner's travel (n x 3 x 4). The warp's mean :math:`\bar w` is the zero errors'
    :math:`\sum_i c_i o_i` with :math:`c = (1/t_f, -1/t_f, -1/t_r, 1/t_r)`; each corner
    alone would be :math:`o_i = \bar w / c_i`, and the one whose :math:`T_i o_i` is closest
    to the quiet samples' mean residual is taken.
    """
    # A lateral load transfer twists the tyres (their deflections differ front and rear); a
    # longitudinal one (braking, a grade) does not.
    ay = u[INPUTS.index("ay")]
    quiet = np.abs(ay) < QUIET_ACCELERATION
    if np.count_nonzero(quiet) < 50:
        return None
    d = u[input_index(TRAVEL)][:, quiet]
    tf, tr = vehicle.geometry.track_front, vehicle.geometry.track_rear
    c = np.array([1 / tf, -1 / tf, -1 / tr, 1 / tr])
    warps = c @ d
    warp = float(np.mean(warps))
    offsets = warp / c
    if np.min(np.abs(offsets)) < TRAVEL_ZERO_LIMIT:
        return None
    # A zero is there from the first sample to the last: the quiet samples' first and
    # second halves agree (a sensor that drifts or sticks on the way is a fault, not a zero).
    first, second = np.array_split(warps, 2)
    if abs(first.mean() - second.mean()) > CONSISTENT * abs(warp):
        return None
    # The pitch and roll rows tell the corner (each corner's offset has its own pair of
    # signs); the vertical row is left out: an az bias of 0.05 m/s^2 moves it as much as a
    # few mm of one corner's travel.
    weight = 1.0 / np.sqrt(np.asarray(vehicle.filter.constraint_noise_density, float))
    weight[0] = 0.0
    mean_r = r[quiet].mean(axis=0)
    mean_T = T[quiet].mean(axis=0)  # (3, 4)
    misfit = [float(np.sum((weight * (mean_r - mean_T[:, i] * offsets[i])) ** 2)) for i in range(4)]
    corner = int(np.argmin(misfit))
    channel = TRAVEL[corner]
    return ModelError(
        name=f"travel zero {channel}",
        keys=(channel,),
        unit="m",
        file_value=(0.0,),
        fitted_value=(float(offsets[corner]),),
        explained=float(1.0 - misfit[corner] / max(np.sum((weight * mean_r) ** 2), 1e-300)),
    )
