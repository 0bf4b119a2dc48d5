"""Estimators that turn logged signals into wheel-load estimates, and C code generation."""

from wheelload.estimators.result import Estimate, StepFlag
from wheelload.estimators.signals import LogError, Signals, read_log, signals_from_frame, write_log
from wheelload.estimators.two_stage import FilterState, Sample, TwoStageKF, step_function

__all__ = [
    "Estimate",
    "FilterState",
    "LogError",
    "Sample",
    "Signals",
    "StepFlag",
    "TwoStageKF",
    "read_log",
    "signals_from_frame",
    "step_function",
    "write_log",
]
