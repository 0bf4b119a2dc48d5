r"""Predictions and regressors of each data kind, built from the suspension model Function.

With the model :math:`z = f(s, \theta)` (four wheel loads from the signals
:math:`s` and the stacked parameters :math:`\theta`):

- drive log: :math:`\hat y = f(s, \theta)` per wheel with a reference load;
- corner rig, wheel i with partner j on its axle:
  :math:`\hat y = f_i(d_i = d_j = d,\ v_i = v) - f_i(0, 0)` (the partner moves
  with it, so the bar is not twisted; other signals are zero on a rig);
- bar rig, axle with wheels L, R:
  :math:`\hat y = f_L(d_L, d_R) - f_L(d_L, d_L)` (everything but the coupling
  between the wheels cancels).

The regressor of a parameter is :math:`\partial \hat y / \partial \theta`,
the CasADi Jacobian of these expressions; no equation is written here.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.identification.data import DataKind, DataSet
from wheelload.estimators.identification.model import WHEELS, SuspensionFitModel
from wheelload.estimators.loops.compiled import CompiledLoop
from wheelload.models.runtime import interrupts

#: Samples per evaluation of the regressors: one chunk's rows (4 wheels x the parameters,
#: and 3 instrument lags) take a few tens of MB whatever the length of the log.
CHUNK = 4096


@dataclass(frozen=True, kw_only=True)
class Prediction:
    """``y = function(s, theta)`` of one data kind, its sample layout and its Jacobian."""

    function: ca.Function  # (s[ns], theta[n_theta]) -> y[rows]
    jacobian: ca.Function  # (s, theta) -> dy/dtheta [rows x n_theta]
    columns: tuple[str, ...]  # data-set signal names stacked into s


def _finish(name: str, s: ca.SX, theta: ca.SX, y: ca.SX, columns) -> Prediction:
    function = ca.Function(name, [s, theta], [y], ["s", "theta"], ["y"])
    jacobian = ca.Function(
        f"{name}_jacobian", [s, theta], [ca.jacobian(y, theta)], ["s", "theta"], ["J"]
    )
    return Prediction(function=function, jacobian=jacobian, columns=tuple(columns))


class RowFunction:
    """Prediction and regressors of one sample, ``(s, theta) -> (y, J)``, over many samples in
    compiled C (:class:`~wheelload.estimators.loops.compiled.CompiledLoop`).

    The per-sample Function is the :class:`Prediction`'s own (its output and
    CasADi Jacobian); the samples are fed from numpy arrays, so no CasADi
    ``map`` over the whole log is built (its sparse output, made dense, took
    about 30 times the regressor matrix itself).
    """

    def __init__(self, pred: Prediction) -> None:
        s, theta = pred.function.sx_in()
        y = ca.densify(pred.function.call([s, theta])[0])
        J = pred.jacobian.call([s, theta])[0]
        step = ca.Function(
            f"{pred.function.name()}_rows", [s, theta], [y, J], ["s", "theta"], ["y", "J"]
        )
        self.rows, self.n_theta = J.shape
        self.row, self.column = step.sparsity_out(1).get_triplet()
        self._loop = CompiledLoop(step, 0, ("s",))

    def __call__(self, s: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predictions (n, rows) and regressors (n, rows, n_theta) at the samples ``s``."""
        _, _, (y, values) = self._loop([], [theta], [s])
        J = np.zeros((s.shape[0], self.rows, self.n_theta))
        J[:, self.row, self.column] = values
        return y, J


def _theta(model: SuspensionFitModel) -> ca.SX:
    return ca.SX.sym("theta", len(model.parameter_names()))


def _require(model: SuspensionFitModel, names: tuple[str, ...], what: str) -> None:
    missing = [n for n in names if n not in model.channel_names()]
    if missing:
        raise ValueError(f"a {what} needs a model with signal '{missing[0]}'")


def drive_prediction(model: SuspensionFitModel) -> Prediction:
    """All four model loads from the log's channels."""
    theta = _theta(model)
    names = model.channel_names()
    s = ca.SX.sym("s", len(names))
    channels = {name: s[i] for i, name in enumerate(names)}
    return _finish("drive", s, theta, model.loads(channels, theta), names)


def corner_prediction(model: SuspensionFitModel, wheel: int) -> Prediction:
    """Load change of one corner driven alone on a rig (bar not twisted, other signals 0)."""
    theta = _theta(model)
    d, v = ca.SX.sym("d"), ca.SX.sym("v")
    name, partner = WHEELS[wheel], WHEELS[wheel ^ 1]
    _require(model, (f"d_{name}", f"d_{partner}", f"v_{name}"), "corner rig")
    moved = {f"d_{name}": d, f"d_{partner}": d, f"v_{name}": v}
    y = model.loads(moved, theta)[wheel] - model.loads({}, theta)[wheel]
    return _finish(f"corner_rig_{wheel}", ca.vertcat(d, v), theta, y, ("d", "v"))


def bar_prediction(model: SuspensionFitModel, axle: int) -> Prediction:
    """Load the bar adds to the left wheel for a travel difference."""
    theta = _theta(model)
    left_d, right_d = ca.SX.sym("d_left"), ca.SX.sym("d_right")
    left, right = WHEELS[2 * axle], WHEELS[2 * axle + 1]
    _require(model, (f"d_{left}", f"d_{right}"), "bar rig")

    def loads(d_right):
        return model.loads({f"d_{left}": left_d, f"d_{right}": d_right}, theta)[2 * axle]

    y = loads(right_d) - loads(left_d)
    return _finish(f"bar_rig_{axle}", ca.vertcat(left_d, right_d), theta, y, ("d_left", "d_right"))


@functools.lru_cache(maxsize=64)
def _prediction(model: SuspensionFitModel, kind: DataKind, location: int) -> Prediction:
    if kind is DataKind.DRIVE:
        return drive_prediction(model)
    if kind is DataKind.CORNER_RIG:
        return corner_prediction(model, location)
    return bar_prediction(model, location)


def prediction(model: SuspensionFitModel, data: DataSet) -> Prediction:
    """The :class:`Prediction` for a data set."""
    return _prediction(model, data.kind, data.location)


@functools.lru_cache(maxsize=64)
def _row_function(model: SuspensionFitModel, kind: DataKind, location: int) -> RowFunction:
    return RowFunction(_prediction(model, kind, location))


def row_function(model: SuspensionFitModel, data: DataSet) -> RowFunction:
    """The compiled :class:`RowFunction` for a data set."""
    return _row_function(model, data.kind, data.location)


@dataclass(frozen=True, kw_only=True, eq=False)
class Rows:
    """The stacked regression rows of all data sets at one parameter point."""

    y: np.ndarray  # (N,) measured
    y_hat: np.ndarray  # (N,) predicted
    J: np.ndarray  # (N, n_theta) regressors
    group: np.ndarray  # (N,) data-set index
    wheel: np.ndarray  # (N,) wheel name per row
    t: np.ndarray  # (N,) time of the sample
    travel: np.ndarray  # (N,) travel of the row's wheel [m] (bar rig: left wheel)
    rate: np.ndarray  # (N,) travel rate of the row's wheel [m/s]
    difference: np.ndarray  # (N,) left minus right travel of the row's axle [m]
    Z: np.ndarray | None = None  # (N, lags, n_theta) instrument regressors (:func:`instruments`)


#: Samples between a row and its instruments: the noise of a backward-differenced
#: rate at k, (e_k - e_{k-1}) / dt, shares no sample with the samples L >= 2 away.
#: Several lags keep the instruments correlated with the motion at every frequency
#: below half the sample rate (at 100 Hz the lag-2 mean alone is blind near 12.5 Hz,
#: the wheel-hop band; lags 3 and 4 see it).
INSTRUMENT_LAGS = (2, 3, 4)


def instruments(s: np.ndarray, lag: int, index: np.ndarray | None = None) -> np.ndarray:
    r"""Instrument signals: the mean of the samples ``lag`` before and after.

    .. math:: \tilde s_k = (s_{k-L} + s_{k+L}) / 2

    Sensor noise that is white, or white and differenced once (a travel
    rate from the difference of noisy travels), at sample k is independent
    of the noise at k - L and k + L for L >= 2, while the motion is
    correlated with it: regressors evaluated at :math:`\tilde s` for the
    lags :data:`INSTRUMENT_LAGS` are instruments for those at :math:`s`
    (Söderström & Stoica, System Identification, 1989, ch. 8). Edge samples
    repeat the first and last sample. ``index``: the samples k wanted (default all).
    """
    n = s.shape[0]
    index = np.arange(n) if index is None else index
    before = s[np.clip(index - lag, 0, n - 1)]
    after = s[np.clip(index + lag, 0, n - 1)]
    return 0.5 * (before + after)


def _signal(model: SuspensionFitModel, data: DataSet, name: str) -> np.ndarray:
    """A data set's samples of signal ``name``; an optional channel it lacks is 0."""
    if name in data.signals or name not in model.optional:
        return data.signals[name]
    return np.zeros((len(data), 1))


def _rows(
    model: SuspensionFitModel,
    data: DataSet,
    group: int,
    samples: np.ndarray,
    theta: np.ndarray,
    instrumented: bool,
) -> Rows:
    """The rows of the used ``samples`` (indices with a finite target) of one data set."""
    pred = prediction(model, data)
    rows_of = row_function(model, data)
    full = np.hstack([_signal(model, data, name)[samples] for name in pred.columns])
    y_hat, jac = rows_of(full, theta)
    mask = np.isfinite(data.target[samples])
    sample, row = np.nonzero(mask)
    Z = None
    if instrumented:
        if data.kind is DataKind.DRIVE:
            columns = [_signal(model, data, name) for name in pred.columns]
            lagged = []
            for lag in INSTRUMENT_LAGS:
                tilde = np.hstack([instruments(c, lag, samples) for c in columns])
                lagged.append(rows_of(tilde, theta)[1])
            instrument = np.stack(lagged, axis=2)  # (n, rows, lags, n_theta)
        else:  # rig rows: their own instruments
            instrument = np.repeat(jac[:, :, None, :], len(INSTRUMENT_LAGS), axis=2)
        Z = instrument[sample, row]
    travel, rate, difference = _row_signals(data, samples, sample, row)
    return Rows(
        y=data.target[samples][sample, row],
        y_hat=y_hat[sample, row],
        J=jac[sample, row, :],
        Z=Z,
        group=np.full(sample.size, group),
        wheel=np.asarray(data.rows)[row],
        t=data.t[samples][sample],
        travel=travel,
        rate=rate,
        difference=difference,
    )


def used_samples(data: DataSet, start: int = 0, stop: int | None = None) -> np.ndarray:
    """Indices of the samples in ``[start, stop)`` (default all) with a finite target in
    some row."""
    block = data.target[start:stop]
    return start + np.flatnonzero(np.isfinite(block).any(axis=1))


def chunks(
    model: SuspensionFitModel,
    sets: tuple[DataSet, ...],
    theta: np.ndarray,
    instrumented: bool = False,
    size: int = CHUNK,
) -> Iterator[Rows]:
    """The rows of :func:`evaluate`, in the same order, the used samples of ``size``
    samples at a time (a data set on disk: its pages dropped after each)."""
    for index, data in enumerate(sets):
        for start, stop in data.blocks(size):
            used = used_samples(data, start, stop)
            if used.size:
                rows = _rows(model, data, index, used, theta, instrumented)
                interrupts.check()  # a Ctrl-C the regressors' CasADi call swallowed
                yield rows


#: Samples per data set in the rows a chunked fit keeps for its figures.
SAMPLED = 5000


def sampled_rows(
    model: SuspensionFitModel, sets: tuple[DataSet, ...], theta: np.ndarray, limit: int = SAMPLED
) -> Rows:
    """The rows of at most ``limit`` used samples per data set, spread evenly in time (the
    used samples of ranks ``linspace(0, count - 1, limit)`` rounded), a block at a time."""
    parts = []
    for index, data in enumerate(sets):
        count = sum(used_samples(data, a, b).size for a, b in data.blocks(CHUNK))
        ranks = np.arange(count)
        if count > limit:
            ranks = np.linspace(0, count - 1, limit).round().astype(int)
        seen = 0
        for a, b in data.blocks(CHUNK):
            used = used_samples(data, a, b)
            wanted = ranks[(ranks >= seen) & (ranks < seen + used.size)] - seen
            if wanted.size:
                parts.append(_rows(model, data, index, used[wanted], theta, False))
            seen += used.size
    return stack(parts)


def stack(parts: list[Rows]) -> Rows:
    """Rows of several chunks in one."""
    fields = ("y", "y_hat", "J", "group", "wheel", "t", "travel", "rate", "difference")
    values = {name: np.concatenate([getattr(p, name) for p in parts]) for name in fields}
    instrumented = parts[0].Z is not None
    return Rows(**values, Z=np.concatenate([p.Z for p in parts]) if instrumented else None)


def evaluate(
    model: SuspensionFitModel,
    sets: tuple[DataSet, ...],
    theta: np.ndarray,
    instrumented: bool = False,
) -> Rows:
    """Predictions and regressors of every used sample (finite target) at ``theta``, in memory.

    ``instrumented``: also the regressors at the drive logs' instrument
    signals (:func:`instruments`; rig rows are their own instruments).
    """
    parts = [part for part in chunks(model, sets, theta, instrumented) if part.y.size]
    if not parts:
        raise ValueError("no data sample with a measured force or reference load")
    return stack(parts)


def _row_signals(data: DataSet, samples, sample, row):
    """Travel, rate and axle travel difference of each row, for the report's figures."""
    signals = {name: value[samples] for name, value in data.signals.items()}
    if data.kind is DataKind.CORNER_RIG:
        return signals["d"][sample, 0], signals["v"][sample, 0], np.zeros(sample.size)
    if data.kind is DataKind.ARB_RIG:
        left, right = signals["d_left"][sample, 0], signals["d_right"][sample, 0]
        return left, np.zeros(sample.size), left - right

    def column(prefix: str) -> np.ndarray:
        names = [f"{prefix}_{w}" for w in WHEELS]
        if not all(name in signals for name in names):
            return np.full((len(sample), 4), np.nan)
        return np.hstack([signals[name] for name in names])[sample]

    d, v = column("d"), column("v")
    wheel = np.arange(len(sample)), np.asarray(row)
    left = 2 * (wheel[1] // 2)
    return d[wheel], v[wheel], d[wheel[0], left] - d[wheel[0], left + 1]


def structure(model: SuspensionFitModel, sets: tuple[DataSet, ...], theta: np.ndarray):
    """Which parameters the kinds of data in ``sets`` can see, and the symbolic Jacobians.

    ``visible[j]`` is true when the Jacobian column of parameter ``j`` is
    nonzero for some kind at random signal values (a rig difference that
    cancels a parameter exactly leaves it invisible); ``symbolic`` holds the
    SX Jacobian expression and the parameter symbol of each kind.
    """
    seen = {}
    for data in sets:
        seen[(data.kind, data.location)] = prediction(model, data)
    visible = np.zeros(len(theta), bool)
    symbolic = []
    rng = np.random.default_rng(0)
    for pred in seen.values():
        s, symbol = pred.function.sx_in()
        count = 256  # random signs, magnitudes 1e-3 to 1e2 (SI): past any map knot
        probe = rng.choice([-1.0, 1.0], (s.shape[0], count)) * 10.0 ** rng.uniform(
            -3.0, 2.0, (s.shape[0], count)
        )
        jac = np.asarray(pred.jacobian.map(count)(probe, theta))
        visible |= np.abs(jac.reshape(jac.shape[0], count, len(theta))).max(axis=(0, 1)) > 0
        y = pred.function.call([s, symbol])[0]
        symbolic.append((ca.jacobian(y, symbol), symbol))
    return visible, symbolic


def linear_free_set(
    model: SuspensionFitModel, sets: tuple[DataSet, ...], theta: np.ndarray, fixed: frozenset[str]
) -> tuple[list[int], list[int]]:
    """Parameters to fit, and those held because the model is not linear in them jointly.

    Greedy in layout order: a parameter the data depend on joins the free
    set when the Jacobian with respect to the free set stays independent of
    the free set (the prediction stays linear in it); e.g. the bar rate joins
    and its ratio, which multiplies it, is held.
    """
    depends, symbolic = structure(model, sets, theta)
    names = model.parameter_names()
    free: list[int] = []
    nonlinear: list[int] = []
    for j, name in enumerate(names):
        if not depends[j] or name in fixed or name in model.held:
            continue
        trial = [*free, j]
        linear = True
        for J, theta in symbolic:
            block = J[:, trial]
            if ca.depends_on(block, theta[trial]):
                linear = False
                break
        (free if linear else nonlinear).append(j)
    return free, nonlinear
