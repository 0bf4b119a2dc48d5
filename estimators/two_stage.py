"""Two-stage physics-constrained Kalman filter (Siegloff & Choi §III, method A).

State :math:`x = [F_{FL}, F_{FR}, F_{RL}, F_{RR}]`, random walk (eq. 12, 19);
first update with the suspension pseudo-measurement :math:`z = x + v_s`
(eq. 13, 20-22); second update with the rigid-body equilibrium as a soft
constraint :math:`b = A x + w_c` (eq. 17, 23-25). Joseph form throughout.

Tuning is per second (white-noise densities): :math:`Q = q\\,dt\\,I`,
:math:`R_s = r_s/dt\\,I`, :math:`R_c = \\mathrm{diag}(r_c)/dt`.

The per-sample step is one CasADi Function built from the model Functions in
``wheelload.models``; :meth:`TwoStageKF.run` maps it over a log in compiled
code (a generated C loop, the equivalent of ``mapaccum``; see ``compiled``).

Example
-------
>>> kf = TwoStageKF(load_vehicle("sports_car.toml"))
>>> estimates = kf.run(read_log("drive.csv")).to_pandas()
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np
import pandas as pd

from wheelload.estimators.compiled import CompiledLoop
from wheelload.estimators.kalman import (
    predict,
    sequential_update,
    sequential_update_innovations,
    upper,
)
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import Signals, rate_derivatives
from wheelload.models import (
    INPUTS,
    OPTIONAL_INPUTS,
    ModelParameters,
    Vehicle,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.roll_split import SPLIT_NOISE_RATIO, roll_split_function

#: Order of the tuning vector.
TUNING = (
    "process_noise_density",
    "suspension_noise_density",
    "constraint_noise_vertical",
    "constraint_noise_pitch",
    "constraint_noise_roll",
)
STEP_NAME = "wheelload_kf_step"


def tuning_vector(vehicle: Vehicle) -> np.ndarray:
    """The filter tuning of a vehicle file in :data:`TUNING` order."""
    tuning = vehicle.filter
    return np.array(
        [
            tuning.process_noise_density,
            tuning.suspension_noise_density,
            *tuning.constraint_noise_density,
        ]
    )


def _dependency_mask(outputs: ca.SX, inputs: ca.SX, valid: ca.SX) -> ca.SX:
    """1 for each output whose every structurally needed input is valid, else 0."""
    pattern = ca.jacobian(outputs, inputs).sparsity()
    masks = []
    for row in range(outputs.shape[0]):
        needed = [col for col in range(inputs.shape[0]) if pattern.has_nz(row, col)]
        mask = 1
        for col in needed:
            mask = mask * valid[col]
        masks.append(mask)
    return ca.vertcat(*masks)


def _required(valid: ca.SX) -> ca.SX:
    """Validity of the inputs an update cannot do without (optional inputs count as valid)."""
    return ca.vertcat(
        *[1 if name in OPTIONAL_INPUTS else valid[i] for i, name in enumerate(INPUTS)]
    )


def _sanitise(u: ca.SX, valid: ca.SX) -> ca.SX:
    """Replace invalid inputs by zero so that no NaN or Inf enters the arithmetic."""
    return ca.vertcat(*[ca.if_else(valid[i], u[i], 0) for i in range(u.shape[0])])


MAX_INTERVAL = 1e6  # s, longest sample interval taken as valid


def interval_is_valid(dt):
    """1 where the sample interval is finite and positive (NaN compares false)."""
    return ca.logic_and(dt > 0, dt < MAX_INTERVAL)


def model_rows(suspension: ca.Function, equilibrium: ca.Function, u_raw, valid, p):
    """Pseudo-measurement, equilibrium and their masks from raw inputs and validity.

    Returns ``(z, A, b, mask_s, mask_c, dropped)``. An update needs the inputs
    of the paper's model (every term gated off: the Jacobian sparsity of the
    rows with zero gates); a term whose optional input is missing is gated off
    for the sample instead, and ``dropped`` (``wheelload.models.DROPPABLE``
    order) says which.
    """
    u = _sanitise(u_raw, valid)
    gates, dropped = gates_function()(valid, p)
    z = suspension(u, gates, p)
    A, b = equilibrium(u, gates, p)
    paper = ca.DM.zeros(gates.shape)
    mask_s = _dependency_mask(suspension(u, paper, p), u_raw, _required(valid))
    mask_c = _dependency_mask(equilibrium(u, paper, p)[1], u_raw, _required(valid))
    return z, A, b, mask_s, mask_c, dropped


def step_expressions(
    suspension: ca.Function,
    equilibrium: ca.Function,
    *,
    constraint_update=sequential_update_innovations,
):
    """Symbolic inputs and outputs of one filter step built from the model Functions.

    ``constraint_update(x, P, b, A, r_c, mask) -> (x, P, y, S, use)`` is the
    second stage; the default is the soft-constraint Kalman update (eq.
    23-25), one row at a time. Outputs ``innovation`` and
    ``innovation_variance`` (7 each, update order: suspension FL, FR, RL, RR,
    then vertical, pitch, roll) are each row's pre-update innovation and its
    variance S; both are 0 for a row whose inputs are missing.
    """
    x = ca.SX.sym("x", 4)
    P = ca.SX.sym("P", 4, 4)
    u_raw = ca.SX.sym("u", len(INPUTS))
    valid = ca.SX.sym("u_valid", len(INPUTS))
    dt = ca.SX.sym("dt")
    p = ca.SX.sym("p", len(ModelParameters.names()))
    tuning = ca.SX.sym("tuning", len(TUNING))

    z, A, b, mask_s, mask_c, dropped = model_rows(suspension, equilibrium, u_raw, valid, p)
    # A non-positive or non-finite interval skips the whole step: the state is held.
    dt_ok = interval_is_valid(dt)
    dt_safe = ca.if_else(dt_ok, dt, 1.0)
    mask_s = mask_s * dt_ok
    mask_c = mask_c * dt_ok

    Q = tuning[0] * dt_safe * dt_ok * ca.DM.eye(4)
    rs = ca.repmat(tuning[1] / dt_safe, 4, 1)
    rc = tuning[2:5] / dt_safe

    # R_s and R_c are diagonal: row-by-row updates equal the joint ones (eq. 20-25).
    x_pred, P_pred = predict(x, upper(P), Q)
    x_s, P_s, y_s, S_s, use_s = sequential_update_innovations(
        x_pred, P_pred, z, ca.DM.eye(4), rs, mask_s
    )
    x_new, P_new, y_c, S_c, use_c = constraint_update(x_s, P_s, b, A, rc, mask_c)
    # No travel row at all (IMU-only): the weak roll-split row observes the warp.
    mask_split = dt_ok * (1 - mask_s[0]) * (1 - mask_s[1]) * (1 - mask_s[2]) * (1 - mask_s[3])
    r_split = SPLIT_NOISE_RATIO * rc[2:3]
    x_new, P_new = sequential_update(
        x_new, P_new, ca.DM.zeros(1), roll_split_function()(p), r_split, mask_split
    )

    std = ca.sqrt(ca.fmax(ca.diag(P_new), 0))
    residual = b - ca.mtimes(A, x_new)
    used = ca.vertcat(use_s, use_c, (1 - dropped) * dt_ok)
    available = ca.vertcat(mask_s, mask_c)
    innovation = ca.vertcat(y_s, y_c) * available
    innovation_variance = ca.vertcat(S_s, S_c) * available
    inputs = [x, P, u_raw, valid, dt, p, tuning]
    outputs = [x_new, P_new, std, residual, used, z, innovation, innovation_variance]
    return inputs, outputs


STEP_INPUT_NAMES = ["x", "P", "u", "u_valid", "dt", "p", "tuning"]
STEP_OUTPUT_NAMES = [
    "x_next", "P_next", "std", "residual", "used", "z", "innovation", "innovation_variance",
]  # fmt: skip


def step_function(
    suspension: ca.Function | None = None,
    equilibrium: ca.Function | None = None,
    name: str = STEP_NAME,
    *,
    constraint_update=sequential_update_innovations,
) -> ca.Function:
    """The filter step as a CasADi Function (model Functions default to ``wheelload.models``)."""
    inputs, outputs = step_expressions(
        suspension or suspension_function(),
        equilibrium or equilibrium_function(),
        constraint_update=constraint_update,
    )
    # The suspension and equilibrium share the body motion and attitude: one copy.
    outputs = ca.cse(outputs)
    return ca.Function(name, inputs, outputs, STEP_INPUT_NAMES, STEP_OUTPUT_NAMES)


#: The seven update rows in update order (innovation outputs).
UPDATE_ROWS = (
    "suspension_fl", "suspension_fr", "suspension_rl", "suspension_rr",
    "vertical", "pitch", "roll",
)  # fmt: skip


@dataclass(frozen=True, kw_only=True, eq=False)
class Innovations:
    """Pre-update innovations of the seven update rows of ``n`` samples (:data:`UPDATE_ROWS`).

    ``innovation`` :math:`y` [N, N, N m], ``variance`` :math:`S` [its unit^2],
    both 0 where the row's inputs are missing; ``used`` is True where the
    row updated the state.
    """

    t: np.ndarray  # (n,)
    innovation: np.ndarray  # (n, 7)
    variance: np.ndarray  # (n, 7)
    used: np.ndarray  # (n, 7) bool

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t, innovation_<row>.., variance_<row>.., used_<row>..``."""
        columns = {"t": self.t}
        columns.update(
            {f"innovation_{r}": self.innovation[:, i] for i, r in enumerate(UPDATE_ROWS)}
        )
        columns.update({f"variance_{r}": self.variance[:, i] for i, r in enumerate(UPDATE_ROWS)})
        columns.update({f"used_{r}": self.used[:, i] for i, r in enumerate(UPDATE_ROWS)})
        return pd.DataFrame(columns)


@dataclass(frozen=True)
class FilterState:
    """Explicit filter state: loads ``x`` [N] and covariance ``P`` [N^2]."""

    x: np.ndarray
    P: np.ndarray


@dataclass(frozen=True, kw_only=True)
class Sample:
    """One sample of the signals used by the filter (SI units).

    ``rates`` (wx wy wz), ``rate_dots`` (their derivative) and ``hub``
    (az_fl .. az_rr) are optional; an absent group is missing (NaN) in
    :meth:`vector`, which drops the terms that need it.
    """

    d: np.ndarray  # (4,) travel
    v: np.ndarray  # (4,) travel rate
    acc: np.ndarray  # (3,) ax, ay, az specific force
    vx: float
    rates: np.ndarray | None = None  # (3,) wx, wy, wz body rates [rad/s], if logged
    rate_dots: np.ndarray | None = None  # (3,) their derivative [rad/s^2], if logged
    hub: np.ndarray | None = None  # (4,) az_fl..az_rr hub specific force, if logged

    def vector(self) -> np.ndarray:
        def given(values: np.ndarray | None, size: int) -> np.ndarray:
            return np.full(size, np.nan) if values is None else np.asarray(values, float)

        return np.concatenate(
            [
                self.d,
                self.v,
                self.acc,
                [self.vx],
                given(self.rates, 3),
                given(self.rate_dots, 3),
                given(self.hub, 4),
            ]
        ).astype(float)


def input_matrix(signals: Signals) -> np.ndarray:
    """The per-sample inputs of a log in :data:`INPUTS` order, shape (len(INPUTS), n).

    Optional channels the log lacks are NaN (their terms are dropped).
    """
    n = len(signals)

    def optional(values: np.ndarray | None, width: int) -> np.ndarray:
        return np.full((width, n), np.nan) if values is None else values.T

    rows = np.vstack(
        [
            signals.d.T,
            signals.v.T,
            signals.acc.T,
            signals.vx[None, :],
            optional(signals.rates, 3),
            rate_derivatives(signals).T,
            optional(signals.hub, 4),
        ]
    )
    if rows.shape[0] != len(INPUTS):
        raise RuntimeError(f"input_matrix builds {rows.shape[0]} rows for {len(INPUTS)} INPUTS")
    return rows


def flags_from_used(used: np.ndarray) -> np.ndarray:
    """Per-sample :class:`StepFlag` bits from the ``used`` output (7 + 4 dropped terms x n).

    A ``used`` of only the seven update rows (a method without model terms)
    gives their bits only.
    """
    skipped = used < 0.5
    bits = np.array([flag.value for flag in StepFlag.update_flags()[: used.shape[0]]])
    return (skipped * bits[:, None]).sum(axis=0).astype(np.int64)


class TwoStageKF:
    """Two-stage physics-constrained Kalman filter for the four wheel loads.

    Parameters
    ----------
    vehicle
        Vehicle parameters and filter tuning.
    static
        Static wheel loads [N] used as pseudo-measurement offsets and initial
        estimate; default: the vehicle file's static load distribution.
    step
        The step Function, e.g. ``step_function(suspension=...)`` with another
        model; default :func:`step_function`.
    """

    name = "two-stage KF"

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        static: np.ndarray | None = None,
        step: ca.Function | None = None,
    ) -> None:
        self.vehicle = vehicle
        self.parameters = ModelParameters.from_vehicle(vehicle, static)
        self.p = self.parameters.vector()
        self.tuning = tuning_vector(vehicle)
        self._step = step or step_function()

    def initial_state(self) -> FilterState:
        """Static loads with covariance ``initial_std^2 I``."""
        x0 = np.array(self.parameters.static(), dtype=float)
        return FilterState(x0, self.vehicle.filter.initial_std**2 * np.eye(4))

    def step(self, state: FilterState, sample: Sample, dt: float) -> tuple[FilterState, Estimate]:
        """One prediction and both updates; returns the new state and the estimate."""
        u = sample.vector()
        valid = np.isfinite(u).astype(float)
        flat = np.concatenate(
            [
                state.x,
                np.ravel(state.P, order="F"),
                np.nan_to_num(u),
                valid,
                [dt],
                self.p,
                self.tuning,
            ]
        )
        x, P, std, residual, used = np.split(
            np.asarray(self._flat_step(flat)).ravel(), self._flat_splits
        )[:5]
        flags = flags_from_used(used.reshape(-1, 1))
        if not 0.0 < dt < MAX_INTERVAL:
            flags |= StepFlag.STEP_REJECTED
        estimate = Estimate(
            t=np.array([np.nan]),
            loads=x.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=flags,
        )
        return FilterState(x, P.reshape(4, 4, order="F")), estimate

    @functools.cached_property
    def _flat_step(self) -> ca.Function:
        """The step with inputs and outputs stacked into one vector each (one cheap call)."""
        inputs = self._step.sx_in()
        outputs = self._step.call(inputs)
        return ca.Function(
            f"{self._step.name()}_flat",
            [ca.vertcat(*[ca.vec(i) for i in inputs])],
            [ca.vertcat(*[ca.vec(o) for o in outputs])],
        )

    @functools.cached_property
    def _flat_splits(self) -> np.ndarray:
        return np.cumsum([self._step.nnz_out(i) for i in range(self._step.n_out())])[:-1]

    def run(self, signals: Signals, state: FilterState | None = None) -> Estimate:
        """Filter a whole log in compiled code; same numbers as repeated :meth:`step`."""
        return self._run(signals, state, with_covariance=False)[0]

    def run_with_covariance(
        self, signals: Signals, state: FilterState | None = None
    ) -> tuple[Estimate, np.ndarray]:
        """As :meth:`run`, also returning the posterior covariances, shape (n, 4, 4)."""
        return self._run(signals, state, with_covariance=True)[:2]

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        """This filter's step looped over a log in C (state x, P carried)."""
        return CompiledLoop(self._step, 2, ("u", "u_valid", "dt"))

    def _run(self, signals: Signals, state: FilterState | None, with_covariance: bool):
        state = state or self.initial_state()
        u = input_matrix(signals).T
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = sample_intervals(signals.t)[:, None]
        _, history, (std, residual, used, _, innovation, variance) = self._loop(
            [state.x, state.P],
            [self.p, self.tuning],
            [u, valid, dt],
            record=(0, 1) if with_covariance else (0,),
        )
        estimate = Estimate(
            t=signals.t.copy(),
            loads=history[0],
            std=std,
            residual=residual,
            flags=flags_from_used(used.T) | signals.input_flags(),
        )
        covariances = history[1].reshape(-1, 4, 4) if with_covariance else None
        innovations = Innovations(
            t=signals.t.copy(), innovation=innovation, variance=variance, used=used[:, :7] > 0.5
        )
        return estimate, covariances, innovations

    def run_innovations(
        self, signals: Signals, state: FilterState | None = None
    ) -> tuple[Estimate, Innovations]:
        """As :meth:`run`, also returning every update row's innovation and its variance.

        The innovations of the sequential filter are independent standard
        normals under the model once divided by :math:`\\sqrt{S}`, so the log
        likelihood of the tuning is :math:`-\tfrac12 \\sum (\\log 2\\pi S + y^2 / S)`
        over the rows used (Mehra 1970).
        """
        estimate, _, innovations = self._run(signals, state, with_covariance=False)
        return estimate, innovations


def sample_intervals(t: np.ndarray) -> np.ndarray:
    """Interval before each sample; the first sample reuses the first interval."""
    dt = np.diff(t)
    return np.concatenate([dt[:1], dt])
