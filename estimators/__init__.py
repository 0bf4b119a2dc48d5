"""Estimators that turn logged signals into wheel-load estimates, and C code generation.

The settings and tools in ``_LAZY_MODULES`` are imported on first use (the MHE's
OSQP and scipy.sparse are slow to import, and a command that does not run the MHE
should not pay for them).
"""

from wheelload.estimators.kf.projection import ProjectionKF, Weighting
from wheelload.estimators.kf.step import step_function
from wheelload.estimators.kf.two_stage import FilterState, TwoStageKF
from wheelload.estimators.lazy_names import lazy_names
from wheelload.estimators.logs.signals import (
    LogError,
    Signals,
    read_log,
    signals_from_frame,
    write_log,
)
from wheelload.estimators.protocol import Sample
from wheelload.estimators.result import Estimate, StepFlag

#: Names imported on first use, by module: settings and tools the command line and the
#: studies take from this face (they reach estimators through the registry).
_LAZY_MODULES = {
    "wheelload.estimators.mhe.settings": (
        "Arrival",
        "BiasStates",
        "Constraint",
        "Loss",
        "MheSettings",
        "ResidualLoss",
    ),
    "wheelload.estimators.mhe.estimator": ("MovingHorizonEstimator",),
    "wheelload.estimators.mhe.qp": ("OSQP_INFINITY", "MheWorkspace"),
    "wheelload.estimators.kf.guard": (
        "FAULT_CHANNELS",
        "GUARDS_OFF",
        "GuardSettings",
        "guard_settings_for",
    ),
    "wheelload.estimators.identification.offsets": ("check_still_period", "corner_weight_loads"),
    "wheelload.estimators.protocol": ("DEFAULT_MODEL", "SuspensionModel"),
    "wheelload.estimators.kf.step": ("UPDATE_ROWS",),
    "wheelload.estimators.kf.tuning": (
        "TUNED_DENSITIES",
        "TUNING_INDEX",
        "noise_densities",
        "nominal_interval",
    ),
    "wheelload.estimators.logs.inputs": ("input_matrix",),
    "wheelload.estimators.family.standstill": ("WeighSettings", "sprung_geometry", "weigh"),
    "wheelload.estimators.kf.log_stream": ("LogStream", "scan_log"),
    "wheelload.estimators.samples": ("step_through",),
}
__getattr__, _LAZY_NAMES = lazy_names(__name__, _LAZY_MODULES)


__all__ = [
    "Estimate",
    "FilterState",
    "LogError",
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
    *_LAZY_NAMES,
]
