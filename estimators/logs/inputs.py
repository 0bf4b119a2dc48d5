"""A log's signals as the models' per-sample input vector (:data:`~wheelload.models.INPUTS`).

Every estimator built from the model Functions takes its inputs in this order; an optional
channel the log lacks is NaN, so the terms that need it are dropped.

Example
-------
>>> u = input_matrix(read_log("drive.csv"))  # shape (len(INPUTS), n)
"""

from __future__ import annotations

import numpy as np

from wheelload.estimators.logs.signals import (
    DEFAULT_RATE_FILTER,
    RateDerivativeFilter,
    rate_derivatives,
)
from wheelload.estimators.types import Signals
from wheelload.models import INPUTS


def input_blocks(
    signals: Signals, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
) -> list[tuple[np.ndarray | None, int]]:
    """The log's arrays in :data:`INPUTS` order: ``(array (n, width) or None, width)``;
    the body-rate derivatives, where not logged, from ``rate_filter`` (a vehicle file's:
    ``RateDerivativeFilter.of(vehicle)``).

    None where the log lacks an optional channel group (its inputs are NaN).
    The arrays are the log's own (no copies): the batched C driver reads them in place.
    """
    return [
        (signals.d, 4),
        (signals.v, 4),
        (signals.acc, 3),
        (signals.vx[:, None], 1),
        (signals.rates, 3),
        (rate_derivatives(signals, rate_filter), 3),
        (signals.hub, 4),
    ]


def input_matrix(
    signals: Signals, rate_filter: RateDerivativeFilter = DEFAULT_RATE_FILTER
) -> np.ndarray:
    """The per-sample inputs of a log in :data:`INPUTS` order, shape (len(INPUTS), n)
    (``rate_filter`` as :func:`input_blocks`).

    Optional channels the log lacks are NaN (their terms are dropped).
    """
    n = len(signals)
    rows = np.vstack(
        [
            np.full((width, n), np.nan) if values is None else values.T
            for values, width in input_blocks(signals, rate_filter)
        ]
    )
    if rows.shape[0] != len(INPUTS):
        raise RuntimeError(f"input_matrix builds {rows.shape[0]} rows for {len(INPUTS)} INPUTS")
    return rows
