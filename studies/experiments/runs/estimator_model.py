"""The vehicle model the studies build the estimators on (``wheelload study --model``).

:attr:`EstimatorModel.FULL` is the vehicle file as it is: every ``[model]`` term it
switches on and the online payload estimate (``[filter.payload]``). :attr:`EstimatorModel.PAPER`
is Siegloff & Choi's model (eq. 9, 14-16): every model term off
(:func:`~wheelload.studies.experiments.equilibrium_residuals.paper_model`) and the file's
mass and CG held (``[filter.payload] estimate = false``), which the paper does not estimate.
The KF, the projection KF and the MHE are built on it; the family methods too, where
``--suspension full`` gives them the KF's own model. The plant always keeps the file.

Example
-------
>>> kf = build("kf", on_model(load_vehicle(path), EstimatorModel.PAPER))
"""

from __future__ import annotations

import dataclasses

from wheelload.models import Vehicle
from wheelload.studies.experiments.equilibrium_residuals import paper_model
from wheelload.studies.experiments.runs.choices import EstimatorModel


def on_model(vehicle: Vehicle, model: EstimatorModel) -> Vehicle:
    """``vehicle`` as the estimators see it on ``model`` (module docstring)."""
    if model is EstimatorModel.FULL:
        return vehicle
    bare = paper_model(vehicle)
    payload = dataclasses.replace(bare.filter.payload, estimate=False)
    return bare.replace(filter=dataclasses.replace(bare.filter, payload=payload))
