"""Estimators that turn logged signals into wheel-load estimates, and C code generation.

Every name of this face is imported on first use, by module (``_LAZY_MODULES``): the
MHE's OSQP and scipy.sparse are slow to import, and a command pays only for the
modules it runs (one log's estimate needs neither the projection KF nor the MHE).
"""

from wheelload.models.files.lazy_names import lazy_names

#: Names imported on first use, by module: the filters, settings and tools the command line
#: and the studies take from this face (they reach estimators through the registry).
_LAZY_MODULES = {
    "wheelload.estimators.kf.projection": ("ProjectionKF", "Weighting"),
    "wheelload.estimators.kf.step": ("step_function",),
    "wheelload.estimators.kf.step_cache": ("UPDATE_ROWS",),
    "wheelload.estimators.kf.two_stage": ("FilterState", "TwoStageKF"),
    "wheelload.estimators.logs.signals": (
        "LogError",
        "Signals",
        "read_log",
        "signals_from_frame",
        "write_log",
    ),
    "wheelload.estimators.protocol": ("DEFAULT_MODEL", "Sample", "SuspensionModel"),
    "wheelload.estimators.result": ("Estimate", "StepFlag"),
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
    "wheelload.estimators.kf.tuning": (
        "TUNED_DENSITIES",
        "TUNING",
        "noise_densities",
        "nominal_interval",
    ),
    "wheelload.estimators.logs.inputs": ("input_matrix",),
    "wheelload.estimators.family.standstill": ("WeighSettings", "sprung_geometry", "weigh"),
    "wheelload.estimators.family.tyres.forces": ("TyreSettings",),
    "wheelload.estimators.kf.log_stream": ("LogStream", "scan_log"),
    "wheelload.estimators.kernels.order_statistics": ("linear_percentile", "median", "percentile"),
    "wheelload.estimators.samples": ("step_through",),
}
__getattr__, _LAZY_NAMES = lazy_names(__name__, _LAZY_MODULES)

__all__ = list(_LAZY_NAMES)
