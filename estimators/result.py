"""Estimator output: loads, standard deviations, constraint residuals and flags."""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import pandas as pd

WHEELS = ("fl", "fr", "rl", "rr")
RESIDUALS = ("residual_vertical", "residual_pitch", "residual_roll")


class StepFlag(enum.IntFlag):
    """Per-sample status bits: which updates were skipped for missing inputs.

    ``STEP_REJECTED``: the sample interval is not a positive finite number
    (``TwoStageKF.step`` and the generated C), or, in C only, the step's
    result would not be finite; the state is then held and every update flag
    is set too.
    """

    SUSPENSION_FL_SKIPPED = 1
    SUSPENSION_FR_SKIPPED = 2
    SUSPENSION_RL_SKIPPED = 4
    SUSPENSION_RR_SKIPPED = 8
    VERTICAL_SKIPPED = 16
    PITCH_SKIPPED = 32
    ROLL_SKIPPED = 64
    STEP_REJECTED = 128

    @classmethod
    def update_flags(cls) -> tuple[StepFlag, ...]:
        """The seven update flags in the order of the filter's ``used`` output."""
        return tuple(cls)[:7]


@dataclass(frozen=True, kw_only=True, eq=False)
class Estimate:
    """Wheel-load estimates of ``n`` samples, wheel order FL, FR, RL, RR.

    ``residual`` is :math:`b - A x` after the update [N, N m, N m].

    ``has_std`` is False for a method that has no standard deviation (an
    algebraic or deterministic estimator): its ``std`` is then all zeros (never
    NaN) and :meth:`to_pandas` leaves the ``fz_std_*`` columns out.
    """

    t: np.ndarray  # (n,)
    loads: np.ndarray  # (n, 4) N
    std: np.ndarray  # (n, 4) N
    residual: np.ndarray  # (n, 3)
    flags: np.ndarray  # (n,) StepFlag bits
    has_std: bool = True

    def __len__(self) -> int:
        return len(self.t)

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t, fz_fl.., fz_std_fl.. (if has_std), residual_vertical.., flags``."""
        columns = {"t": self.t}
        columns.update({f"fz_{w}": self.loads[:, i] for i, w in enumerate(WHEELS)})
        if self.has_std:
            columns.update({f"fz_std_{w}": self.std[:, i] for i, w in enumerate(WHEELS)})
        columns.update({name: self.residual[:, i] for i, name in enumerate(RESIDUALS)})
        columns["flags"] = self.flags
        return pd.DataFrame(columns)
