"""A log's signals as the models' per-sample input vector (:data:`~wheelload.models.INPUTS`).

Every estimator built from the model Functions takes its inputs in this order; an optional
channel the log lacks is NaN, so the terms that need it are dropped.

Example
-------
>>> u = input_matrix(read_log("drive.csv"))  # shape (len(INPUTS), n)
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.logs.signals import Signals, rate_derivatives
from wheelload.models import INPUTS


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
