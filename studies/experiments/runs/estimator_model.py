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
import enum

from wheelload.models import Vehicle
from wheelload.studies.experiments.equilibrium_residuals import paper_model


class EstimatorModel(enum.Enum):
    """The estimators' vehicle model: the file's (``full``) or the paper's (``paper``)."""

    FULL = "full"  # the vehicle file's [model] terms and the online payload estimate
    PAPER = "paper"  # every [model] term off, the payload estimate off

    @classmethod
    def parse(cls, text: str) -> EstimatorModel:
        """``"full"`` or ``"paper"`` (command line); anything else names the choices."""
        for member in cls:
            if member.value == text:
                return member
        choices = ", ".join(member.value for member in cls)
        raise ValueError(f"--model {text!r}: unknown vehicle model; choose one of {choices}")


#: What each model is, in the words of the report and ``--help``.
WORDS = {
    EstimatorModel.FULL: "the vehicle file's [model] terms and the online payload estimate",
    EstimatorModel.PAPER: "Siegloff & Choi's: every [model] term off, the payload estimate "
    "off ([filter.payload] estimate = false)",
}
#: The same, in a table's caption.
SHORT_WORDS = {
    EstimatorModel.FULL: "the file's model terms, the online payload",
    EstimatorModel.PAPER: "every model term off, the payload estimate off",
}


def on_model(vehicle: Vehicle, model: EstimatorModel) -> Vehicle:
    """``vehicle`` as the estimators see it on ``model`` (module docstring)."""
    if model is EstimatorModel.FULL:
        return vehicle
    bare = paper_model(vehicle)
    payload = dataclasses.replace(bare.filter.payload, estimate=False)
    return bare.replace(filter=dataclasses.replace(bare.filter, payload=payload))
