"""Residual of the equilibrium model on a plant's own loads, per row (issue 9 checks).

:math:`r = b(u) - A x_{ref}` with the reference loads of a simulated log and
the model inputs the estimators would see (:func:`input_matrix`), once for
the vehicle file's model terms and once for the paper's model (every term
off). A term that models the plant better lowers the residual's RMS.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from wheelload.estimators.identification.tuning import noise_densities
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.models import (
    ModelParameters,
    ModelTerms,
    Vehicle,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.measurement_noise import measurement_noise_function

ROWS = ("vertical", "pitch", "roll")


def with_terms(vehicle: Vehicle, **switches: bool) -> Vehicle:
    """The vehicle with the ``[model]`` switches replaced (others kept)."""
    return vehicle.replace(model=dataclasses.replace(vehicle.model, **switches))


def paper_model(vehicle: Vehicle) -> Vehicle:
    """The vehicle with every model term off (Siegloff & Choi's model)."""
    off = {field.name: False for field in dataclasses.fields(ModelTerms)}
    return with_terms(vehicle, **off)


def _model_inputs(vehicle: Vehicle, frame: pd.DataFrame):
    """Signals, sample count, inputs, gates and parameters of a simulated log's frame."""
    # The plant's own frames (a test flips a sign on purpose to show the residual
    # catches it): the reader's wiring checks would refuse that frame first.
    signals = signals_from_frame(frame, source="<plant>", wiring_checks=False)
    if signals.reference is None:
        raise ValueError("the frame has no reference loads fz_fl .. fz_rr")
    n = len(signals)
    p = ModelParameters.from_vehicle(vehicle).vector()
    u = input_matrix(signals)
    valid = np.isfinite(u).astype(float)
    gates = np.asarray(gates_function().map(n)(valid, p)[0])
    return signals, n, np.nan_to_num(u), gates, p


def equilibrium_residuals(vehicle: Vehicle, frame: pd.DataFrame) -> np.ndarray:
    """Per-sample residual ``b - A x_ref`` (n, 3) of a simulated log's reference loads."""
    signals, n, u, gates, p = _model_inputs(vehicle, frame)
    A, b = equilibrium_function().map(n)(u, gates, p)
    A = np.asarray(A)[:, :4]
    return np.asarray(b).T - signals.reference @ A.T


def residual_rms(vehicle: Vehicle, frame: pd.DataFrame) -> dict[str, float]:
    """RMS of each row's residual [N, N m, N m]."""
    residual = equilibrium_residuals(vehicle, frame)
    return dict(zip(ROWS, np.sqrt(np.mean(residual**2, axis=0)).tolist(), strict=True))


def suspension_residuals(vehicle: Vehicle, frame: pd.DataFrame) -> np.ndarray:
    """Per-sample pseudo-measurement error :math:`z(u) - F_{ref}` (n, 4) [N], FL FR RL RR."""
    signals, n, u, gates, p = _model_inputs(vehicle, frame)
    z = np.asarray(suspension_function().map(n)(u, gates, p)).T
    return z - signals.reference


def suspension_residual_rms(vehicle: Vehicle, frame: pd.DataFrame) -> float:
    """Pooled RMS [N] of the pseudo-measurement :math:`z(u)` against the reference loads."""
    return float(np.sqrt(np.mean(suspension_residuals(vehicle, frame) ** 2)))


def noise_calibration(vehicle: Vehicle, frame: pd.DataFrame) -> dict[str, float]:
    r"""Per update row, the mean over the samples of :math:`e^2 / R`: the actual error
    :math:`e` on the reference loads (pseudo-measurement :math:`z - F_{ref}`, pooled over the
    wheels; each equilibrium row's :math:`b - A F_{ref}`) over the variance :math:`R` the
    KF assumes for it (:func:`~wheelload.models.measurement_noise.measurement_noise_function`
    with the file's densities at the log's interval, eq. 13, 17). 1 is a row the filter
    weighs as its error is; the ratio of an equilibrium row's value to the suspension's is
    the :math:`R_c` scale that would weigh the two updates as their errors are (white-noise
    view: the errors' correlation in time is left out)."""
    signals, n, u, _, _ = _model_inputs(vehicle, frame)
    valid = np.isfinite(input_matrix(signals)).astype(float)
    dt = float(np.median(np.diff(signals.t)))
    densities = noise_densities(vehicle)[1:]  # without the process noise, DENSITIES order
    R_s, R_c = measurement_noise_function().map(n)(u, valid, densities, dt)
    suspension = suspension_residuals(vehicle, frame) ** 2 / np.asarray(R_s).T
    rows = equilibrium_residuals(vehicle, frame) ** 2 / np.asarray(R_c).T
    result = {"suspension": float(np.mean(suspension))}
    result.update(zip(ROWS, np.mean(rows, axis=0).tolist(), strict=True))
    return result
