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
    # Bits 16-19: a model term (wheelload.models.terms) switched on in the
    # vehicle file was dropped for this sample because an input it needs is
    # missing (the updates themselves went ahead without it).
    BODY_INERTIA_DROPPED = 1 << 16  # no wx_dot, wy_dot (no body rates in the log)
    UNSPRUNG_INERTIA_DROPPED = 1 << 17  # a hub accelerometer az_* missing
    ROAD_FRAME_OR_LINKS_DROPPED = (
        1 << 18
    )  # road frame or link loads: a travel, IMU axis or vx missing
    IMU_TERMS_DROPPED = 1 << 19  # lever arm (no rates) or mounting (an IMU axis missing)

    @classmethod
    def update_flags(cls) -> tuple[StepFlag, ...]:
        """The flags in the order of the filter's ``used`` output.

        Seven updates (suspension FL..RR, vertical, pitch, roll), then the four
        droppable terms in ``wheelload.models.DROPPABLE`` order.
        """
        return (*tuple(cls)[:7], *_TERM_FLAGS)


_TERM_FLAGS = (
    StepFlag.BODY_INERTIA_DROPPED,
    StepFlag.UNSPRUNG_INERTIA_DROPPED,
    StepFlag.ROAD_FRAME_OR_LINKS_DROPPED,
    StepFlag.IMU_TERMS_DROPPED,
)


@dataclass(frozen=True, kw_only=True, eq=False)
class Estimate:
    """Wheel-load estimates of ``n`` samples, wheel order FL, FR, RL, RR.

    ``residual`` is :math:`b - A x` after the update [N, N m, N m].
    """

    t: np.ndarray  # (n,)
    loads: np.ndarray  # (n, 4) N
    std: np.ndarray  # (n, 4) N
    residual: np.ndarray  # (n, 3)
    flags: np.ndarray  # (n,) StepFlag bits

    def __len__(self) -> int:
        return len(self.t)

    def to_pandas(self) -> pd.DataFrame:
        """Columns ``t, fz_fl.., fz_std_fl.., residual_vertical.., flags``."""
        columns = {"t": self.t}
        columns.update({f"fz_{w}": self.loads[:, i] for i, w in enumerate(WHEELS)})
        columns.update({f"fz_std_{w}": self.std[:, i] for i, w in enumerate(WHEELS)})
        columns.update({name: self.residual[:, i] for i, name in enumerate(RESIDUALS)})
        columns["flags"] = self.flags
        return pd.DataFrame(columns)
