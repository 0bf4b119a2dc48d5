"""A plain numpy, per-sample loop of the same filter in joint form: test oracle and baseline.

One update with the stacked measurement instead of two sequential ones:

.. math:: H = \\begin{bmatrix} I_4 \\\\ A \\end{bmatrix}, \\quad
          y = \\begin{bmatrix} z \\\\ b \\end{bmatrix}, \\quad
          R = \\mathrm{blkdiag}(R_s, R_c)

For independent measurement noises this equals the two-stage update exactly
(Siegloff & Choi §III-D), so it checks the compiled filter and gives the
benchmark a conventional implementation to compare with. Like the step, the first
sample's prediction carries no prior information, :math:`P^-_0 = (m g)^2 I`. It takes z and b
from the model Functions, and :math:`R_s, R_c` from the filter's noise Function
(:mod:`wheelload.models.measurement_noise`) at each sample's interval; it
handles no missing samples.
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.kf.tuning import TUNING
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.protocol import sample_intervals
from wheelload.estimators.types import Signals
from wheelload.models import (
    GRAVITY,
    ModelParameters,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.models.measurement_noise import DENSITIES, measurement_noise_function


def pseudo_measurements(
    signals: Signals, p: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z (n, 4), A (3, 4) and b (n, 3) of a whole log, mapped in CasADi."""
    n = len(signals)
    u = input_matrix(signals)
    valid = np.isfinite(u).astype(float)
    gates = np.asarray(gates_function().map(n)(valid, p)[0])
    u = np.nan_to_num(u)
    z = np.asarray(suspension_function().map(n)(u, gates, p)).T
    A, b = equilibrium_function().map(n)(u, gates, p)
    return z, np.asarray(A)[:, :4], np.asarray(b).T


def measurement_noises(signals: Signals, tuning: np.ndarray, dt: np.ndarray) -> np.ndarray:
    r"""Diagonal of :math:`\mathrm{blkdiag}(R_s, R_c)` (n, 7) of a whole log at intervals ``dt``."""
    u = input_matrix(signals)
    valid = np.isfinite(u).astype(float)
    densities = TUNING.values(tuning, DENSITIES)
    noise = measurement_noise_function().map(len(signals))
    R_s, R_c = noise(np.nan_to_num(u), valid, densities, dt[None, :])
    return np.vstack([np.asarray(R_s), np.asarray(R_c)]).T


def joint_filter(signals: Signals, p: np.ndarray, tuning: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """Loads (n, 4) from the joint (stacked) Joseph-form update, one sample at a time."""
    z, A, b = pseudo_measurements(signals, p)
    dt = sample_intervals(signals.t)
    R_diagonal = measurement_noises(signals, tuning, dt)
    H = np.vstack([np.eye(4), A])
    I = np.eye(4)
    x, P = x0.astype(float).copy(), np.zeros((4, 4))
    weight = p[ModelParameters.names().index("mass")] * GRAVITY
    q = TUNING.value(tuning, "process_noise_density")
    out = np.empty((len(signals), 4))
    for k in range(len(signals)):
        P = P + q * dt[k] * I if k else weight**2 * I
        R = np.diag(R_diagonal[k])
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        x = x + K @ (np.concatenate([z[k], b[k]]) - H @ x)
        IKH = I - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        P = 0.5 * (P + P.T)
        out[k] = x
    return out
