"""Error metrics of the main paper (Siegloff & Choi §IV-B, eq. 26-34).

.. math:: e_i = \\hat F_{z,i} - F^{ref}_{z,i}, \\quad
          RMSE_i = \\sqrt{\\tfrac1N \\sum_k e_i^2}, \\quad
          RMSE_{\\%,i} = 100\\, RMSE_i / \\overline{F^{ref}_{z,i}}

P95 is the 95th percentile of :math:`|e|`, Max its maximum; the pooled row
pools all wheels and samples (eq. 31-34). Only wheels with a reference (a
reference column with a finite value) are scored: a log with references on
the front wheels only is scored on FL and FR, per wheel and pooled over them.

Example
-------
>>> table = wheel_metrics(estimate.loads, signals.reference)
>>> table.loc["pooled", "RMSE"]
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators import percentile
from wheelload.models.conventions import WHEELS

if TYPE_CHECKING:
    import pandas as pd

COLUMNS = ("RMSE", "RMSE %", "P95", "Max")


def _row(errors: np.ndarray, mean_reference: float) -> list[float]:
    absolute = np.abs(errors)
    rmse = float(np.sqrt(np.mean(errors**2)))
    return [
        rmse,
        100.0 * rmse / mean_reference,
        float(percentile(absolute, 95)),
        float(absolute.max()),
    ]


def wheel_metrics(
    estimate: np.ndarray, reference: np.ndarray, source: str = "estimate"
) -> pd.DataFrame:
    """Per-wheel and pooled RMSE [N], RMSE [%], P95 [N], Max [N] (eq. 27-34).

    Rows: the wheels with a reference, then ``pooled``. Samples where an
    estimate or reference of those wheels is not finite are left out (the
    count is in the ``samples`` column). ``source`` names the log in errors.
    """
    estimate = np.asarray(estimate, float)
    reference = np.asarray(reference, float)
    if estimate.shape != reference.shape or estimate.ndim != 2 or estimate.shape[1] != 4:
        raise ValueError(
            f"estimate {estimate.shape} and reference {reference.shape} must both be (n, 4)"
        )
    wheels = np.flatnonzero(np.any(np.isfinite(reference), axis=0))
    if wheels.size == 0:
        raise ValueError(no_reference_message(source))
    estimate, reference = estimate[:, wheels], reference[:, wheels]
    names = [WHEELS[i] for i in wheels]
    keep = np.all(np.isfinite(estimate) & np.isfinite(reference), axis=1)
    if not keep.any():
        raise ValueError(no_sample_message(source, names))
    errors = estimate[keep] - reference[keep]
    return metrics_table(errors, reference[keep].mean(axis=0), names)


def metrics_table(errors: np.ndarray, means: np.ndarray, names: list[str]) -> pd.DataFrame:
    """The table of :func:`wheel_metrics` from the errors (samples x wheels) of the kept
    samples and the wheels' mean reference loads (also used chunk by chunk)."""
    import pandas as pd

    rows = [_row(errors[:, i], means[i]) for i in range(len(names))]
    rows.append(_row(errors.ravel(), float(means.mean())))
    table = pd.DataFrame(rows, index=[*names, "pooled"], columns=COLUMNS)
    table["samples"] = int(errors.shape[0])
    return table


def no_reference_message(source: str) -> str:
    """The error of :func:`wheel_metrics` for a log without a finite reference."""
    return f"{source}: no wheel has a finite reference load"


def no_sample_message(source: str, names: list[str]) -> str:
    """The error of :func:`wheel_metrics` when no sample has estimate and reference."""
    return (
        f"{source}: no sample has a finite estimate and reference on all of "
        f"{', '.join(n.upper() for n in names)} (the wheels with a reference)"
    )


def pooled_metrics(estimate: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """Pooled RMSE, RMSE %, P95 and Max over all wheels and samples (eq. 31-34)."""
    return wheel_metrics(estimate, reference).loc["pooled", list(COLUMNS)].to_dict()


def pooled_force_error(estimate: np.ndarray, reference: np.ndarray) -> tuple[float, float]:
    """Pooled RMSE of ``estimate`` against ``reference`` (n, 4) [N] and the reference's pooled
    RMS [N], over the samples where both are finite (the tyre forces' metric: their mean
    can be zero, so the % is of the RMS, not of the mean as for the loads)."""
    estimate, reference = np.asarray(estimate, float), np.asarray(reference, float)
    keep = np.isfinite(estimate) & np.isfinite(reference)
    errors = (estimate - reference)[keep]
    return float(np.sqrt(np.mean(errors**2))), float(np.sqrt(np.mean(reference[keep] ** 2)))


def normalized_rms_error(estimate: np.ndarray, reference: np.ndarray) -> np.ndarray:
    r"""The corner-based paper's NRMS per wheel [%] (§IV, Table I): the RMSE over the
    largest magnitude of the reference, :math:`\rho_e = 100 \sqrt{\sum_i (\hat\tau_i -
    \tau_i)^2 / N} / \max_i |\tau_i|`, over the samples where both are finite; NaN for a
    wheel whose reference is zero throughout."""
    estimate, reference = np.asarray(estimate, float), np.asarray(reference, float)
    keep = np.isfinite(estimate) & np.isfinite(reference)
    errors = np.where(keep, estimate - reference, 0.0)
    count = np.maximum(keep.sum(axis=0), 1)
    largest = np.max(np.where(keep, np.abs(reference), 0.0), axis=0)
    rmse = np.sqrt(np.sum(errors**2, axis=0) / count)
    return np.where(largest > 0.0, 100.0 * rmse / np.where(largest > 0.0, largest, 1.0), np.nan)
