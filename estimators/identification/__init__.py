"""Identification of the suspension maps and tuning of the filter from rig data and drive logs.

Regressors are Jacobians of the model Functions in ``wheelload.models``
(never a second copy of the equations); the tuning maximises the likelihood
of the filter's own innovations.
"""

from wheelload.estimators.identification.data import (
    DataKind,
    DataSet,
    drive_gates,
    read_drive,
    read_rig,
)
from wheelload.estimators.identification.fit import FitLoss, FitSettings, Identification, identify
from wheelload.estimators.identification.model import (
    SuspensionFitModel,
    default_model,
    piecewise_model,
)

__all__ = [
    "DataKind",
    "DataSet",
    "FitLoss",
    "FitSettings",
    "Identification",
    "SuspensionFitModel",
    "default_model",
    "drive_gates",
    "identify",
    "piecewise_model",
    "read_drive",
    "read_rig",
]
