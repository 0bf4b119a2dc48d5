"""Identification of the suspension maps and tuning of the filter from rig data and drive logs.

Regressors are Jacobians of the model Functions in ``wheelload.models``
(never a second copy of the equations); the tuning maximises the likelihood
of the filter's own innovations.

The names below are imported on first use: the KF's still-period offsets
(``offsets``) live in this package, and a command that estimates a log must not
pay for the fits' scipy and pandas.
"""

from wheelload.models.runtime.lazy_names import lazy_names

#: Names imported on first use, by module.
_LAZY_MODULES = {
    "wheelload.estimators.identification.data": (
        "DataKind",
        "DataSet",
        "drive_gates",
        "read_drive",
        "read_rig",
    ),
    "wheelload.estimators.identification.fit": (
        "FitLoss",
        "FitSettings",
        "Identification",
        "identify",
    ),
    "wheelload.estimators.identification.model": (
        "SuspensionFitModel",
        "default_model",
        "piecewise_model",
    ),
}
__getattr__, __dir__, __all__ = lazy_names(__name__, _LAZY_MODULES)
