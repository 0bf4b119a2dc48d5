"""Estimators that turn logged signals into wheel-load estimates, and C code generation.

This face is the contract a user and the studies build on: the protocol and result
types, the registry (``build``, the method table), the log I/O, each method's options
dataclass with the settings its fields take (MHE, guards, tyres, weighing), and the
lean whole-log reader of the compiled methods (its scan's parts, ``LogScan`` and
``ThinnedInputs``, are found here too, for the studies' one-read estimate, but are not
the contract: they are documented with their module). Implementations stay in their modules;
studies reach them through :func:`build` (benchmarks excepted).

Every name of this face is imported on first use, by module (``_LAZY_MODULES``): the
MHE's OSQP and scipy.sparse are slow to import, and a command pays only for the
modules it runs (one log's estimate needs neither the projection KF nor the MHE).
"""

from wheelload.models.runtime.lazy_names import lazy_names

#: Names imported on first use, by module: the contract the command line and the studies
#: take from this face.
_LAZY_MODULES = {
    "wheelload.estimators.protocol": ("Estimator", "MethodInfo"),
    "wheelload.estimators.suspension_choice": ("DEFAULT_MODEL", "SuspensionModel"),
    "wheelload.estimators.types": ("LogError", "Sample", "Signals"),
    "wheelload.estimators.result": ("Estimate", "StepFlag"),
    "wheelload.estimators.registry": (
        "UnknownMethodError",
        "UnknownOptionError",
        "build",
        "method",
        "methods",
        "tyre_methods",
    ),
    "wheelload.estimators.logs.signals": ("read_log", "signals_from_frame", "write_log"),
    # Each method's options (build's keywords) and the settings their fields take.
    "wheelload.estimators.kf.method": ("KfOptions", "ProjectionOptions"),
    "wheelload.estimators.mhe.method": ("MheOptions",),
    "wheelload.estimators.family.algebraic": ("AlgebraicOptions",),
    "wheelload.estimators.family.quarter_car": ("QuarterCarOptions",),
    "wheelload.estimators.family.strong_tracking_ukf": ("StrongTrackingOptions",),
    "wheelload.estimators.family.ycoo": ("YcooOptions",),
    "wheelload.estimators.family.umvf": ("UmvfOptions",),
    "wheelload.estimators.family.road_angle": ("RoadAngleOptions",),
    "wheelload.estimators.family.corner": ("CornerOptions",),
    "wheelload.estimators.family.tyres.forces": (
        "TyreForcesOptions",
        "TyreOptions",
        "TyreSettings",
    ),
    "wheelload.estimators.kernels.c_emitter": ("Precision",),
    "wheelload.estimators.mhe.settings": (
        "Arrival",
        "BiasStates",
        "Constraint",
        "Loss",
        "MheSettings",
        "ResidualLoss",
    ),
    "wheelload.estimators.guards.settings": (
        "FAULT_CHANNELS",
        "GUARDS_OFF",
        "GuardSettings",
        "guard_settings_for",
    ),
    "wheelload.estimators.family.standstill": ("WeighSettings", "sprung_geometry", "weigh"),
    "wheelload.estimators.kf.log_stream": ("LogStream", "scan_log"),
    "wheelload.estimators.kernels.order_statistics": ("linear_percentile", "percentile"),
}
#: Names the studies' one-read estimate takes through this door that are not the contract
#: (the log scan's parts): found on first use, not listed in ``__all__`` or ``dir()``.
_INTERNAL = {"wheelload.estimators.kf.log_stream": ("LogScan", "ThinnedInputs")}
__getattr__, __dir__, _LAZY_NAMES = lazy_names(__name__, _LAZY_MODULES, _INTERNAL)

__all__ = list(_LAZY_NAMES)
