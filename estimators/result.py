"""Estimator output: loads, standard deviations, constraint residuals and flags."""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import pandas as pd

WHEELS = ("fl", "fr", "rl", "rr")
RESIDUALS = ("residual_vertical", "residual_pitch", "residual_roll")


class StepFlag(enum.IntFlag):
    """Per-sample status bits: which updates were skipped, and why.

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
    # Guards (estimators/guard.py), bits 8-15, in the order of the step's ``status`` output.
    INNOVATION_GATED = 1 << 8  # an update row skipped: y^2 > gate * S
    GATE_RELEASED = 1 << 9  # a row taken after gate_release_time of rejections
    TRAVEL_IMPLAUSIBLE = 1 << 10  # a travel or travel rate out of range: treated as missing
    ACCELERATION_IMPLAUSIBLE = 1 << 11  # |a| above max_acceleration: treated as missing
    SPEED_IMPLAUSIBLE = 1 << 12  # |vx| above max_speed: treated as missing
    TRAVEL_FAULT = 1 << 13  # a travel channel isolated as faulty: dropped
    IMU_FAULT = 1 << 14  # an accelerometer axis isolated as faulty: dropped
    COVARIANCE_LIMITED = 1 << 15  # the covariance floor or ceiling acted

    @classmethod
    def update_flags(cls) -> tuple[StepFlag, ...]:
        """The seven update flags in the order of the filter's ``used`` output."""
        return tuple(cls)[:7]

    @classmethod
    def guard_flags(cls) -> tuple[StepFlag, ...]:
        """The eight guard flags in the order of the filter's ``status`` output."""
        return tuple(flag for flag in cls if 1 << 8 <= flag.value < 1 << 16)


FAULT_COLUMNS = ("channel", "start", "end", "statistic")


@dataclass(frozen=True, kw_only=True)
class SensorFault:
    """An isolated sensor fault: channel, first and last flagged time [s], peak statistic."""

    channel: str
    start: float
    end: float
    statistic: float


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
    sensor_faults: tuple[SensorFault, ...] = ()  # isolated sensor faults, in time order

    @property
    def faults(self) -> pd.DataFrame:
        """The ``faults`` table: ``channel, start, end, statistic``, one row per fault."""
        return pd.DataFrame(
            {
                "channel": pd.Series([f.channel for f in self.sensor_faults], dtype=object),
                "start": pd.Series([f.start for f in self.sensor_faults], dtype=float),
                "end": pd.Series([f.end for f in self.sensor_faults], dtype=float),
                "statistic": pd.Series([f.statistic for f in self.sensor_faults], dtype=float),
            },
            columns=list(FAULT_COLUMNS),
        )

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
