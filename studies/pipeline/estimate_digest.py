"""What ``wheelload estimate`` tells about a log's estimates, gathered chunk by chunk.

:class:`EstimateDigest` takes the estimates in consecutive chunks (the whole
log as one chunk, or the chunks of the lean whole-log path) and keeps the
summary's figures: per-wheel mean, min, max and mean standard deviation, the
status-bit counts, the negative loads and, against the log's reference loads,
the errors of the samples scored (the 95th percentile needs all of them: an
:class:`~wheelload.studies.pipeline.error_store.ErrorStore`, in memory for a short log,
on disk for a long one). No second pass over the estimates. With the whole log as one
chunk the figures equal those computed on the whole arrays to the bit.

Example
-------
>>> digest = EstimateDigest(samples=len(t), reference_wheels=present)
>>> digest.add(loads, std, flags, reference)
>>> digest.metrics("drive.csv")
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wheelload.estimators import StepFlag
from wheelload.studies.metrics import COLUMNS, WHEELS, no_reference_message, no_sample_message
from wheelload.studies.pipeline.error_store import ErrorStore

if TYPE_CHECKING:
    import pandas as pd

_SUSPENSION = (StepFlag.SUSPENSION_FL_SKIPPED, StepFlag.SUSPENSION_FR_SKIPPED,
               StepFlag.SUSPENSION_RL_SKIPPED, StepFlag.SUSPENSION_RR_SKIPPED)  # fmt: skip


class EstimateDigest:
    """Summary figures of estimates added chunk by chunk (module docstring).

    ``samples``: the log's length (sizes the error store; None: not known, the store
    grows); ``reference_wheels``:
    (4,) True for each wheel whose reference has a finite sample in the whole
    log, or None without reference loads.
    """

    def __init__(
        self, *, samples: int | None, reference_wheels: np.ndarray | None, has_std: bool = True
    ) -> None:
        self.n = 0
        self.has_std = has_std
        self.load_sum = np.zeros(4)
        self.load_min = np.full(4, np.inf)
        self.load_max = np.full(4, -np.inf)
        self.std_sum = np.zeros(4)
        self.skipped = 0
        self.assumed = 0
        self.suspension_skipped = np.zeros(4, np.int64)
        self.split = 0
        self.guards = {flag: 0 for flag in StepFlag.guard_flags()}
        self.dropped = {flag: 0 for flag in StepFlag.update_flags()[7:]}
        self.negative_samples = 0
        self.wheels = None if reference_wheels is None else np.flatnonzero(reference_wheels)
        self.scored = 0
        self.reference_sum = None if self.wheels is None else np.zeros(len(self.wheels))
        self.mass_properties = None  # (8,) the last sample's values and std, if estimated
        self.model_errors = ()  # the file check's finding, if any (Estimate.model_errors)
        self.errors = None
        if self.wheels is not None and self.wheels.size:
            self.errors = ErrorStore(len(self.wheels), samples)

    def add(
        self,
        loads: np.ndarray,
        std: np.ndarray,
        flags: np.ndarray,
        reference: np.ndarray | None = None,
    ) -> None:
        """Take the next chunk: loads and std (n, 4), status bits (n,), reference (n, 4)."""
        self.n += len(flags)
        self.load_sum += loads.sum(axis=0)
        self.load_min = np.minimum(self.load_min, loads.min(axis=0))
        self.load_max = np.maximum(self.load_max, loads.max(axis=0))
        self.std_sum += std.sum(axis=0)
        flags = flags.astype(np.int64, copy=False)
        self.skipped += int(np.count_nonzero(flags & StepFlag.skipped_mask()))
        self.assumed += int(np.count_nonzero(flags & StepFlag.assumed_mask()))
        skipped = np.array([(flags & bit) != 0 for bit in _SUSPENSION])
        self.suspension_skipped += skipped.sum(axis=1)
        rejected = (flags & StepFlag.STEP_REJECTED) != 0
        self.split += int((skipped.all(axis=0) & ~rejected).sum())
        for flag in self.guards:
            self.guards[flag] += int(np.count_nonzero(flags & flag))
        for flag in self.dropped:
            self.dropped[flag] += int(np.count_nonzero(flags & flag))
        self.negative_samples += int((loads < 0.0).any(axis=1).sum())
        if self.errors is not None and reference is not None:
            estimate, truth = loads[:, self.wheels], reference[:, self.wheels]
            keep = np.all(np.isfinite(estimate) & np.isfinite(truth), axis=1)
            self.errors.append(estimate[keep] - truth[keep])
            self.reference_sum += truth[keep].sum(axis=0)
            self.scored += int(keep.sum())

    def add_mass_properties(self, values: np.ndarray) -> None:
        """Take the next chunk's online mass properties and their std, (n, 8): keeps the last."""
        if len(values):
            self.mass_properties = np.array(values[-1], float)

    def means(self) -> np.ndarray:
        """Mean load per wheel [N]."""
        return self.load_sum / self.n

    def mean_std(self) -> np.ndarray:
        """Mean standard deviation per wheel [N]."""
        return self.std_sum / self.n

    def metrics(self, source: str) -> pd.DataFrame:
        """The table of :func:`~wheelload.studies.metrics.wheel_metrics`; ValueError as it.

        Once only: the error store is overwritten (see :meth:`.ErrorStore.rows`).
        """
        import pandas as pd

        names, rows = self.metric_rows(source)
        table = pd.DataFrame(rows, index=names, columns=COLUMNS)
        table["samples"] = self.scored
        return table

    def metric_rows(self, source: str) -> tuple[list[str], list[list[float]]]:
        """:meth:`metrics` as plain rows (no pandas): row names (the wheels scored, then
        ``pooled``) and their :data:`~wheelload.studies.metrics.COLUMNS`. Once only."""
        if self.wheels is None or not self.wheels.size:
            raise ValueError(no_reference_message(source))
        names = [WHEELS[i] for i in self.wheels]
        if self.scored == 0:
            raise ValueError(no_sample_message(source, names))
        return [*names, "pooled"], self.errors.rows(self.reference_sum / self.scored)
