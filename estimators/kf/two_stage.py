"""Two-stage physics-constrained Kalman filter (Siegloff & Choi §III, method A): the filter object.

The per-sample step is one CasADi Function (:mod:`wheelload.estimators.kf.step`: random-walk
prediction, suspension update eq. 20-22, soft equilibrium update eq. 23-25, guards) built from
the model Functions in ``wheelload.models``, with the tuning of
:mod:`wheelload.estimators.kf.tuning`; :meth:`TwoStageKF.run` maps it over a log in compiled
code (a generated C loop, the equivalent of ``mapaccum``; see ``compiled``), :meth:`TwoStageKF.step`
runs one sample in compiled C and :meth:`TwoStageKF.reference_step` through CasADi's virtual
machine.

Example
-------
>>> kf = TwoStageKF(load_vehicle("sports_car.toml"))
>>> estimates = kf.run(read_log("drive.csv")).to_pandas()
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from wheelload.estimators.guards import monitor_state
from wheelload.estimators.guards import settings as guard
from wheelload.estimators.guards.monitor_state import MONITOR_SIZE
from wheelload.estimators.guards.settings import GuardSettings
from wheelload.estimators.kf.step_cache import (
    N_CARRIED,
    STEP_OUTPUT_NAMES,
    UPDATE_ROWS,
    default_step_function,
)
from wheelload.estimators.kf.tuning import (
    DEFAULT_SAMPLE_INTERVAL,
    TUNING,
    nominal_interval,
    tuning_vector,
)
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import RateDerivativeFilter
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.result import Estimate, SensorFault, StepFlag
from wheelload.estimators.types import Sample, Signals
from wheelload.models import GRAVITY, INPUTS, ModelParameters, Vehicle
from wheelload.models.input_validity import MAX_INTERVAL
from wheelload.models.loaded_vehicle import PAYLOAD_STATES, mass_properties

if TYPE_CHECKING:
    import pandas as pd

    from wheelload.estimators.logs.model_error import Diagnosis


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
        import pandas as pd

        columns = {"t": self.t}
        columns.update(
            {f"innovation_{r}": self.innovation[:, i] for i, r in enumerate(UPDATE_ROWS)}
        )
        columns.update({f"variance_{r}": self.variance[:, i] for i, r in enumerate(UPDATE_ROWS)})
        columns.update({f"used_{r}": self.used[:, i] for i, r in enumerate(UPDATE_ROWS)})
        return pd.DataFrame(columns)


@dataclass(frozen=True, eq=False)
class FileCheck:
    """The vehicle file checked against one log (:meth:`TwoStageKF.file_check`): the
    diagnosis, and for a named file parameter the loads' change [N] (n, 4) the estimate's σ
    is widened by (None without one)."""

    diagnosis: Diagnosis
    load_change: np.ndarray | None


@dataclass(frozen=True)
class FilterState:
    """Explicit filter state: loads ``x`` [N], covariance ``P`` [N^2], fault monitor ``m``."""

    x: np.ndarray
    P: np.ndarray
    m: np.ndarray = field(default_factory=lambda: np.zeros(MONITOR_SIZE))


def flags_from_used(used: np.ndarray) -> np.ndarray:
    """Per-sample :class:`StepFlag` bits from the ``used`` output (7 + 4 dropped terms x n).

    A ``used`` of only the seven update rows (a method without model terms)
    gives their bits only.
    """
    skipped = used < 0.5
    bits = np.array([flag.value for flag in StepFlag.update_flags()[: used.shape[0]]])
    return (skipped * bits[:, None]).sum(axis=0).astype(np.int64)


def flags_from_outputs(used: np.ndarray, status: np.ndarray) -> np.ndarray:
    """Per-sample flags from the ``used`` (7 x n) and ``status`` (8 x n) outputs."""
    bits = np.array([flag.value for flag in StepFlag.guard_flags()])
    guarded = ((status > 0.5) * bits[:, None]).sum(axis=0).astype(np.int64)
    return flags_from_used(used) | guarded


_INTERVAL_INDEX = TUNING.index("sample_interval")
_NO_TIME = np.array([np.nan])  # the time of a single step's estimate (shared, read-only)
_NO_TIME.flags.writeable = False


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
    check_file
        Before a whole-log :meth:`run`, ask the model-error channel
        (:mod:`~wheelload.estimators.logs.model_error`) whether a vehicle-file parameter or
        a corner's travel zero explains the log's residuals: a travel zero is taken off
        the travel for the run, a file parameter widens the reported σ by the loads'
        change it implies; either is in ``Estimate.model_errors``. The per-sample
        :meth:`step` and :meth:`live` filter without it (they see one sample at a time).
    """

    name = "two-stage KF"

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        static: np.ndarray | None = None,
        step: ca.Function | None = None,
        guard_settings: GuardSettings | None = None,
        sample_interval: float | None = None,
        check_file: bool = True,
    ) -> None:
        self.vehicle = vehicle
        self.rate_filter = RateDerivativeFilter.of(vehicle)  # body-rate derivatives
        self.check_file = check_file
        self._static = static
        self.parameters = ModelParameters.from_vehicle(vehicle, static)
        self.p = self.parameters.vector()
        if guard_settings is None:
            guard_settings = guard.guard_settings_for(vehicle)
        self.guard_settings = guard_settings
        self.sample_interval = sample_interval
        self.tuning = tuning_vector(
            vehicle, sample_interval or DEFAULT_SAMPLE_INTERVAL, guard_settings
        )
        self._given_step = step

    @functools.cached_property
    def step_function(self) -> ca.Function:
        """The step Function: the constructor's, or :func:`step_function` (loaded from disk
        when built before, :func:`default_step_function`), on first use."""
        return default_step_function() if self._given_step is None else self._given_step

    @property
    def default_step(self) -> bool:
        """Whether the step is :func:`step_function` with its defaults (none was given)."""
        return self._given_step is None

    def tuning_for(self, sample_interval: float) -> np.ndarray:
        """:attr:`tuning` with the nominal interval ``sample_interval`` [s]."""
        if not 0.0 < sample_interval < MAX_INTERVAL:
            raise ValueError(f"sample interval must be > 0 s and finite, got {sample_interval}")
        tuning = np.array(self.tuning, float)
        tuning[_INTERVAL_INDEX] = sample_interval
        return tuning

    def state_mass_properties(self, state: FilterState) -> np.ndarray:
        """The loaded car's ``[m', δx, y_c', h']`` that ``state`` carries (its payload states;
        the file's car for the initial state): the ``mass_properties`` :meth:`run` reports."""
        theta = np.asarray(state.m, float)[monitor_state.PAYLOAD]
        return np.asarray(_mass_properties_function()(self.p, theta), float).ravel()

    def initial_state(self) -> FilterState:
        """Static loads with covariance ``initial_std^2 I`` (at most ``(m g)^2``)."""
        x0 = np.array(self.parameters.static(), dtype=float)
        weight = self.parameters.mass * GRAVITY
        variance = min(self.vehicle.filter.initial_std, weight) ** 2
        return FilterState(x0, variance * np.eye(4))

    def step(self, state: FilterState, sample: Sample, dt: float) -> tuple[FilterState, Estimate]:
        """One prediction and both updates; returns the new state and the estimate.

        The measurement noise uses the ``sample_interval`` given to the
        constructor; without one, ``dt`` itself (a gap then shrinks it).
        Runs the step Function in compiled C on preallocated buffers
        (:mod:`wheelload.estimators.loops.fast_step`); the same numbers as
        :meth:`reference_step`.
        """
        fast = self._fast_step
        if self.sample_interval is None:  # else set once in _fast_step
            nominal = dt if 0.0 < dt < MAX_INTERVAL else self.tuning[_INTERVAL_INDEX]
            fast.set_interval(_INTERVAL_INDEX, nominal)
        x, P, m, std, residual, flags = fast.call_sample(state.x, state.P, state.m, sample, dt)
        estimate = Estimate(
            t=_NO_TIME,
            loads=x.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=np.array([flags], dtype=np.int64),
        )
        return FilterState(x, P, m), estimate

    def live(self, state: FilterState | None = None):
        """A :class:`~wheelload.estimators.loops.fast_step.LiveFilter` from ``state`` (default:
        initial).

        The lean per-sample path: the state stays in the compiled step's
        buffer and each update returns views, not new objects; the same
        numbers as :meth:`step` and :meth:`reference_step`.
        """
        from wheelload.estimators.loops.fast_step import LiveFilter

        state = state or self.initial_state()
        return LiveFilter(
            self._fast_step,
            state.x,
            state.P,
            state.m,
            interval_index=None if self.sample_interval is not None else _INTERVAL_INDEX,
            default_interval=float(self.tuning[_INTERVAL_INDEX]),
            max_interval=MAX_INTERVAL,
        )

    def timed(self, settings=None, *, first_interval: float | None = None, on_output=None):
        """A :class:`~wheelload.estimators.kf.rewind.TimedFilter` from the initial state:
        time-stamped measurements, each predicted to its own time, late ones by rewind and
        replay (:mod:`wheelload.estimators.kf.rewind`).

        ``settings``: a :class:`~wheelload.estimators.kf.rewind.RewindSettings` (ring size,
        oldest rewind, speed hold); the measurement noise follows the constructor's
        ``sample_interval`` (else the tuning's default), as :meth:`run` with that interval;
        ``first_interval`` [s] is the prediction before the first measurement (default that
        interval; :meth:`run` uses the log's first interval).
        """
        from wheelload.estimators.kf.rewind import RewindSettings, TimedFilter, timed_tuning
        from wheelload.estimators.loops.fast_step import LiveFilter

        nominal = float(self.sample_interval or self.tuning[_INTERVAL_INDEX])
        state = self.initial_state()
        live = LiveFilter(
            self._fast_step, state.x, state.P, state.m, interval_index=None,
            default_interval=nominal, max_interval=MAX_INTERVAL,
        )  # fmt: skip
        live.set_fixed(self.p, timed_tuning(self.tuning_for(nominal)))
        return TimedFilter(
            live,
            settings or RewindSettings(),
            nominal if first_interval is None else first_interval,
            on_output,
        )

    def run_timed(self, t: np.ndarray, inputs: np.ndarray, latency=None, settings=None, *,
                  first_interval: float | None = None,
                  input_flags: np.ndarray | None = None):  # fmt: skip
        """A long table through :meth:`timed`: rows in order of arrival at times ``t`` [s],
        ``inputs`` (n, INPUTS) NaN where a channel has no new value (a log's
        ``input_matrix(signals).T``), ``latency`` [s] per channel, a vector or a mapping of
        channel names (:func:`~wheelload.estimators.kf.rewind.measurements`);
        ``input_flags`` (n,) per row, a log's ``signals.input_flags()``, ORed into the flags
        of the row's measurements as :meth:`run` does. Returns a
        :class:`~wheelload.estimators.kf.rewind.TimedRun`."""
        from wheelload.estimators.kf.rewind import measurement_rows, run_timed

        stamps, channels, rows = measurement_rows(t, inputs, latency)
        return run_timed(
            lambda record: self.timed(
                settings, first_interval=first_interval, on_output=record
            ),  # fmt: skip
            stamps,
            channels,
            None if input_flags is None else np.asarray(input_flags, np.int64)[rows],
        )

    @functools.cached_property
    def _step(self) -> ca.Function:
        """:attr:`step_function` without the fault monitor (built on first use)."""
        from wheelload.estimators.kf.step import without_monitor  # the symbolic models

        return without_monitor(self.step_function)

    @functools.cached_property
    def _fast_step(self):
        """The step compiled once (cached by source hash), with this filter's p and tuning."""
        from wheelload.estimators.loops.fast_step import CompiledStep

        fast = CompiledStep(self.step_function, MAX_INTERVAL)
        fast.set_fixed(self.p, self.tuning)
        return fast

    def reference_step(
        self, state: FilterState, sample: Sample, dt: float
    ) -> tuple[FilterState, Estimate]:
        """:meth:`step` through CasADi's virtual machine and numpy: the reference for tests."""
        u = sample.vector()
        valid = np.isfinite(u).astype(float)
        nominal = self.sample_interval or (dt if 0.0 < dt < MAX_INTERVAL else None)
        tuning = self.tuning if nominal is None else self.tuning_for(nominal)
        flat = np.concatenate(
            [
                state.x,
                np.ravel(state.P, order="F"),
                state.m,
                np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0),
                valid,
                [dt],
                self.p,
                tuning,
            ]
        )
        out = np.split(np.asarray(self._flat_step(flat)).ravel(), self._flat_splits)
        x, P, m, std, residual, used = out[:6]
        status = out[STEP_OUTPUT_NAMES.index("status")]
        flags = flags_from_outputs(used.reshape(-1, 1), status.reshape(-1, 1))
        if not 0.0 < dt < MAX_INTERVAL:
            flags |= StepFlag.STEP_REJECTED
        estimate = Estimate(
            t=np.array([np.nan]),
            loads=x.reshape(1, 4),
            std=std.reshape(1, 4),
            residual=residual.reshape(1, 3),
            flags=flags,
        )
        return FilterState(x, P.reshape(4, 4, order="F"), m), estimate

    @functools.cached_property
    def _flat_step(self) -> ca.Function:
        """The step with inputs and outputs stacked into one vector each (one cheap call)."""
        inputs = self.step_function.sx_in()
        outputs = self.step_function.call(inputs)
        return ca.Function(
            f"{self.step_function.name()}_flat",
            [ca.vertcat(*[ca.vec(i) for i in inputs])],
            [ca.vertcat(*[ca.vec(o) for o in outputs])],
        )

    @functools.cached_property
    def _flat_splits(self) -> np.ndarray:
        step = self.step_function
        return np.cumsum([step.nnz_out(i) for i in range(step.n_out())])[:-1]

    def log_tuning(self, signals: Signals) -> np.ndarray:
        """The tuning :meth:`run` filters ``signals`` with: the nominal interval the
        constructor's ``sample_interval`` or the log's median interval; for channels on their
        own clocks (``signals.own_clocks``) the IMU's (``ax``'s own stamps) and
        :meth:`timed`'s interval band, so that each row is filtered at its own time stamp
        as the timed filter does (:mod:`~wheelload.estimators.kf.rewind`)."""
        if not signals.own_clocks:
            return self.tuning_for(self.sample_interval or nominal_interval(signals.t))
        from wheelload.estimators.kf.rewind import timed_tuning

        imu = signals.t[np.isfinite(signals.acc[:, 0])]
        return timed_tuning(self.tuning_for(self.sample_interval or nominal_interval(imu)))

    def run(self, signals: Signals, state: FilterState | None = None) -> Estimate:
        """Filter a whole log in compiled code; same numbers as repeated :meth:`step`.

        The nominal interval is the constructor's ``sample_interval`` or the
        log's median interval (:meth:`log_tuning`). A log of channels on their own clocks
        (``[clock] union``: each row the samples logged at its time stamp, NaN elsewhere)
        is filtered as :meth:`run_timed` filters its rows: each predicted to its own time
        stamp and updated by the rows its channels inform.
        """
        return self._run(signals, state, with_covariance=False)[0]

    def run_with_covariance(
        self, signals: Signals, state: FilterState | None = None
    ) -> tuple[Estimate, np.ndarray]:
        """As :meth:`run`, also returning the posterior covariances, shape (n, 4, 4)."""
        return self._run(signals, state, with_covariance=True)[:2]

    def smooth(self, signals: Signals, state: FilterState | None = None) -> Estimate:
        """Rauch–Tung–Striebel smoothed loads of a whole log (``estimators/kf/smoother.py``)."""
        from wheelload.estimators.kf.smoother import rts_smooth
        from wheelload.models import GATES, equilibrium_function

        filtered, covariances = self.run_with_covariance(signals, state)
        A, _ = equilibrium_function()(np.zeros(len(INPUTS)), np.zeros(len(GATES)), self.p)
        dt = sample_intervals(signals.t)
        tuning = self.log_tuning(signals) if signals.own_clocks else self.tuning
        return rts_smooth(filtered, covariances, dt, self._step, self.p, tuning, A)

    @functools.cached_property
    def _loop(self) -> CompiledLoop:
        """This filter's step looped over a log in C (state x, P, m carried)."""
        return CompiledLoop(self.step_function, N_CARRIED, ("u", "u_valid", "dt"))

    def _run(self, signals: Signals, state: FilterState | None, with_covariance: bool,
             checked: FileCheck | None = None):  # fmt: skip
        if not self.check_file:
            return self._filter(signals, state, with_covariance)
        first = None
        if checked is None:
            first = self._filter(signals, state, with_covariance)
            checked = self.file_check(signals, first[0])
        if np.any(checked.diagnosis.travel_zero):
            first = self._filter(checked.diagnosis.corrected(signals), state, with_covariance)
        estimate, covariances, innovations = first or self._filter(signals, state, with_covariance)
        if checked.load_change is not None:
            std = np.sqrt(estimate.std**2 + checked.load_change**2)
            model_errors = (checked.diagnosis.finding,)
            estimate = dataclasses.replace(estimate, std=std, model_errors=model_errors)
        return estimate, covariances, innovations

    def file_check(self, signals: Signals, estimate: Estimate | None = None) -> FileCheck:
        """The vehicle file checked against ``signals`` (:func:`~wheelload.estimators.logs.
        model_error.diagnose`) on this filter's ``estimate`` of them (default: run here,
        from the initial state, before any correction): the samples about an
        isolated sensor fault and those a guard doubted left out (they are the sensor's, not
        the file's), the car as the payload estimate found it at the end; given static
        loads (a still period, corner weights) have taken the travel zeros."""
        from wheelload.estimators.logs.model_error import diagnose

        if estimate is None:
            estimate = self._filter(signals, None, with_covariance=False)[0]
        diagnosis = diagnose(
            signals,
            self.vehicle,
            exclude=about_faults(signals.t, estimate.sensor_faults, FAULT_MARGIN)
            | (estimate.flags & StepFlag.doubtful_mask() != 0),
            travel_zero=self._static is None,
            mass_properties=None if len(signals) == 0 else estimate.mass_properties[-1],
        )
        change = None
        if diagnosis.finding is not None:
            change = diagnosis.load_change(input_matrix(signals, self.rate_filter))
        return FileCheck(diagnosis=diagnosis, load_change=change)

    def _filter(self, signals: Signals, state: FilterState | None, with_covariance: bool):
        state = state or self.initial_state()
        u = input_matrix(signals, self.rate_filter).T
        valid = np.isfinite(u).astype(float)
        u = np.nan_to_num(u, nan=0.0, posinf=0.0, neginf=0.0)
        dt = sample_intervals(signals.t)[:, None]
        tuning = self.log_tuning(signals)
        _, history, outputs = self._loop(
            [state.x, state.P, state.m],
            [self.p, tuning],
            [u, valid, dt],
            record=(0, 1) if with_covariance else (0,),
        )
        named = dict(zip(STEP_OUTPUT_NAMES[N_CARRIED:], outputs, strict=True))
        used = named["used"]
        estimate = Estimate(
            t=signals.t.copy(),
            loads=history[0],
            std=named["std"],
            residual=named["residual"],
            flags=flags_from_outputs(used.T, named["status"].T) | signals.input_flags(),
            sensor_faults=sensor_faults(signals.t, named["fault"], named["fault_statistic"]),
            mass_properties=named["mass_properties"],
            mass_properties_std=named["mass_properties_std"],
        )
        covariances = history[1].reshape(-1, 4, 4) if with_covariance else None
        innovations = Innovations(
            t=signals.t.copy(),
            innovation=named["innovation"],
            variance=named["innovation_variance"],
            used=used[:, :7] > 0.5,
        )
        return estimate, covariances, innovations

    def run_innovations(
        self,
        signals: Signals,
        state: FilterState | None = None,
        *,
        checked: FileCheck | None = None,
    ) -> tuple[Estimate, Innovations]:
        r"""As :meth:`run`, also returning every update row's innovation and its variance.

        The innovations of the sequential filter are independent standard
        normals under the model once divided by :math:`\sqrt{S}`, so the log
        likelihood of the tuning is :math:`-\tfrac12 \sum (\log 2\pi S + y^2 / S)`
        over the rows used (Mehra 1970).

        ``checked``: the file check of these ``signals`` made before (:meth:`file_check`; a
        tuner runs one log with many densities, and the file is the same for all of them).
        """
        estimate, _, innovations = self._run(signals, state, False, checked)
        return estimate, innovations


#: Seconds about an isolated fault left out of the file check: the parity residual's low
#: pass and confirmation before it, the clear time after (guard defaults, with room).
FAULT_MARGIN = 2.0


def about_faults(t: np.ndarray, faults, margin: float) -> np.ndarray:
    """Samples within ``margin`` of an isolated sensor fault (n,)."""
    near = np.zeros(t.shape, bool)
    for fault in faults:
        near |= (t >= fault.start - margin) & (t <= fault.end + margin)
    return near


def sensor_faults(
    t: np.ndarray, fault: np.ndarray, statistic: np.ndarray
) -> tuple[SensorFault, ...]:
    """One record per isolated fault: ``channel, start, end`` [s] and the peak ``statistic``.

    ``fault`` and ``statistic`` are the step outputs, shape (n, 7), channels
    :data:`~wheelload.estimators.guards.settings.FAULT_CHANNELS`; ``end`` is the time of
    the last flagged sample.
    """
    rows = []
    for j, channel in enumerate(guard.FAULT_CHANNELS):
        on = np.concatenate([[False], fault[:, j] > 0.5, [False]])
        starts = np.flatnonzero(on[1:] & ~on[:-1])
        ends = np.flatnonzero(~on[1:] & on[:-1])
        for start, end in zip(starts, ends, strict=True):
            rows.append(
                SensorFault(
                    channel=channel,
                    start=float(t[start]),
                    end=float(t[end - 1]),
                    statistic=float(np.max(statistic[start:end, j])),
                )
            )
    return tuple(sorted(rows, key=lambda fault: fault.start))


@functools.cache
def _mass_properties_function() -> ca.Function:
    """``(p, payload[4]) -> [m', δx, y_c', h']``
    (:func:`~wheelload.models.loaded_vehicle.mass_properties`)."""
    p_vector, p = ModelParameters.symbolic()
    payload = ca.SX.sym("payload", len(PAYLOAD_STATES))
    return ca.Function("mass_properties", [p_vector, payload], [mass_properties(p, payload)])
