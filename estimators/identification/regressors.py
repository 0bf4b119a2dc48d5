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
from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.estimators.identification.data import DataKind, DataSet
from wheelload.estimators.identification.model import SuspensionModel


@dataclass(frozen=True, kw_only=True)
class Prediction:
    """``y = function(s, theta)`` of one data kind, its sample layout and its Jacobian."""

    function: ca.Function  # (s[ns], theta[n_theta]) -> y[rows]
    jacobian: ca.Function  # (s, theta) -> dy/dtheta [rows x n_theta]
    columns: tuple[str, ...]  # data-set signal names stacked into s


def _zero_signals(model: SuspensionModel) -> dict[str, ca.SX]:
    return {name: ca.SX.zeros(size) for name, size in model.signal_inputs()}


def _finish(name: str, s: ca.SX, theta: ca.SX, y: ca.SX, columns) -> Prediction:
    function = ca.Function(name, [s, theta], [y], ["s", "theta"], ["y"])
    jacobian = ca.Function(
        f"{name}_jacobian", [s, theta], [ca.jacobian(y, theta)], ["s", "theta"], ["J"]
    )
    return Prediction(function=function, jacobian=jacobian, columns=tuple(columns))


def _theta(model: SuspensionModel) -> ca.SX:
    return ca.SX.sym("theta", len(model.parameter_names()))


def drive_prediction(model: SuspensionModel) -> Prediction:
    """All four model loads from the log's signals."""
    theta = _theta(model)
    symbols = {name: ca.SX.sym(name, size) for name, size in model.signal_inputs()}
    s = ca.vertcat(*symbols.values())
    return _finish("drive", s, theta, model.loads(symbols, theta), symbols)


def corner_prediction(model: SuspensionModel, wheel: int) -> Prediction:
    """Load change of one corner driven alone on a rig (bar not twisted)."""
    theta = _theta(model)
    d, v = ca.SX.sym("d"), ca.SX.sym("v")
    partner = wheel ^ 1
    moved = _zero_signals(model)
    if "d" not in moved or "v" not in moved:
        raise ValueError("a corner rig needs a model with inputs 'd' and 'v'")
    d4 = [0] * 4
    d4[wheel] = d4[partner] = d
    v4 = [0] * 4
    v4[wheel] = v
    moved["d"], moved["v"] = ca.vertcat(*d4), ca.vertcat(*v4)
    y = model.loads(moved, theta)[wheel] - model.loads(_zero_signals(model), theta)[wheel]
    return _finish(f"corner_rig_{wheel}", ca.vertcat(d, v), theta, y, ("d", "v"))


def bar_prediction(model: SuspensionModel, axle: int) -> Prediction:
    """Load the bar adds to the left wheel for a travel difference."""
    theta = _theta(model)
    left_d, right_d = ca.SX.sym("d_left"), ca.SX.sym("d_right")
    left = 2 * axle

    def loads(d_right):
        signals = _zero_signals(model)
        d4 = [0] * 4
        d4[left], d4[left + 1] = left_d, d_right
        signals["d"] = ca.vertcat(*d4)
        return model.loads(signals, theta)[left]

    y = loads(right_d) - loads(left_d)
    return _finish(f"bar_rig_{axle}", ca.vertcat(left_d, right_d), theta, y, ("d_left", "d_right"))


@functools.lru_cache(maxsize=64)
def _prediction(model: SuspensionModel, kind: DataKind, location: int) -> Prediction:
    if kind is DataKind.DRIVE:
        return drive_prediction(model)
    if kind is DataKind.CORNER_RIG:
        return corner_prediction(model, location)
    return bar_prediction(model, location)


def prediction(model: SuspensionModel, data: DataSet) -> Prediction:
    """The :class:`Prediction` for a data set."""
    return _prediction(model, data.kind, data.location)


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


def evaluate(model: SuspensionModel, sets: tuple[DataSet, ...], theta: np.ndarray) -> Rows:
    """Predictions and regressors of every used sample (finite target) at ``theta``."""
    parts = []
    for index, data in enumerate(sets):
        pred = prediction(model, data)
        s = np.hstack([data.signals[name] for name in pred.columns])
        rows = np.isfinite(data.target)
        keep = rows.any(axis=1)
        s = s[keep]
        n = s.shape[0]
        if n == 0:
            continue
        y_hat = np.asarray(pred.function.map(n)(s.T, theta)).T  # (n, rows)
        jac = np.asarray(pred.jacobian.map(n)(s.T, theta))  # (rows, n * n_theta)
        jac = jac.reshape(jac.shape[0], n, len(theta)).transpose(1, 0, 2)  # (n, rows, n_theta)
        mask = rows[keep]
        sample, row = np.nonzero(mask)
        travel, rate, difference = _row_signals(data, keep, sample, row)
        parts.append(
            (
                data.target[keep][sample, row],
                y_hat[sample, row],
                jac[sample, row, :],
                np.full(sample.size, index),
                np.asarray(data.rows)[row],
                data.t[keep][sample],
                travel,
                rate,
                difference,
            )
        )
    if not parts:
        raise ValueError("no data sample with a measured force or reference load")
    y, y_hat, J, group, wheel, t, travel, rate, difference = (
        np.concatenate(items) for items in zip(*parts)
    )
    return Rows(
        y=y,
        y_hat=y_hat,
        J=J,
        group=group,
        wheel=wheel,
        t=t,
        travel=travel,
        rate=rate,
        difference=difference,
    )


def _row_signals(data: DataSet, keep, sample, row):
    """Travel, rate and axle travel difference of each row, for the report's figures."""
    signals = {name: value[keep] for name, value in data.signals.items()}
    if data.kind is DataKind.CORNER_RIG:
        return signals["d"][sample, 0], signals["v"][sample, 0], np.zeros(sample.size)
    if data.kind is DataKind.ARB_RIG:
        left, right = signals["d_left"][sample, 0], signals["d_right"][sample, 0]
        return left, np.zeros(sample.size), left - right
    d = signals["d"] if "d" in signals else np.full((len(keep), 4), np.nan)[keep]
    v = signals["v"] if "v" in signals else np.full((len(keep), 4), np.nan)[keep]
    wheel = np.arange(4)[row]
    left = 2 * (wheel // 2)
    return d[sample, wheel], v[sample, wheel], d[sample, left] - d[sample, left + 1]


def structure(model: SuspensionModel, sets: tuple[DataSet, ...], theta: np.ndarray):
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
    model: SuspensionModel, sets: tuple[DataSet, ...], theta: np.ndarray, fixed: frozenset[str]
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
        if not depends[j] or name in fixed:
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
