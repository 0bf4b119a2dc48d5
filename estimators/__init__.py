"""Estimators that turn logged signals into wheel-load estimates, and C code generation.

The MHE's names are imported on first use (OSQP and scipy.sparse are slow to
import, and a command that does not run the MHE should not pay for them).
"""

import importlib

from wheelload.estimators.kf.projection import ProjectionKF, Weighting
from wheelload.estimators.kf.two_stage import FilterState, Sample, TwoStageKF, step_function
from wheelload.estimators.logs.signals import (
    LogError,
    Signals,
    read_log,
    signals_from_frame,
    write_log,
)
from wheelload.estimators.result import Estimate, StepFlag

__all__ = [
    "Arrival",
    "Constraint",
    "Estimate",
    "FilterState",
    "LogError",
    "MheSettings",
    "MovingHorizonEstimator",
    "ProjectionKF",
    "Sample",
    "Signals",
    "StepFlag",
    "TwoStageKF",
    "Weighting",
    "read_log",
    "signals_from_frame",
    "step_function",
    "write_log",
]

_MHE_NAMES = ("Arrival", "Constraint", "MheSettings", "MovingHorizonEstimator")
_LAZY = dict.fromkeys(_MHE_NAMES, "wheelload.estimators.mhe.estimator")


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'wheelload.estimators' has no attribute '{name}'")
