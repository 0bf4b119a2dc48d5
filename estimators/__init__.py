"""Estimators that turn logged signals into wheel-load estimates, and C code generation."""

from wheelload.estimators.mhe import Arrival, Constraint, MheSettings, MovingHorizonEstimator
from wheelload.estimators.projection import ProjectionKF, Weighting
from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import LogError, Signals, read_log, signals_from_frame, write_log
from wheelload.estimators.two_stage import FilterState, Sample, TwoStageKF, step_function

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
