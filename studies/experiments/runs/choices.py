"""What ``wheelload study`` and ``identify-study`` offer, without building anything.

The studies' names, the mhe-vs-kf study's scenarios, window lengths and injected faults, the
estimators' vehicle models and the identification study's drive log: names and plain enums
only (no numerics), so that ``--help`` lists them at once. The heavy modules import them
from here (:mod:`~wheelload.studies.experiments.catalog` checks its registry against
:data:`EXPERIMENT_NAMES` on import).
"""

from __future__ import annotations

import enum

#: The experiments of :mod:`~wheelload.studies.experiments.catalog`, and ``all``.
EXPERIMENT_NAMES = (
    "iso-dlc",
    "nordschleife",
    "hockenheim",
    "ablation",
    "cheon-structural",
    "monte-carlo",
    "mismatch",
    "payload",
    "sigma",
    "vehicles",
    "sensor-errors",
    "tyre-forces",
    "all",
)

#: The mhe-vs-kf equivalence sweep's window lengths.
HORIZONS = (1, 5, 10, 20, 50)

#: The plant scenarios the mhe-vs-kf study simulates when ``--scenarios`` names none.
STUDY_SCENARIOS = ("iso-dlc", "nordschleife", "hockenheim", "wheel-lift")

#: The drive log the identification study identifies from by default.
IDENTIFY_ON = "nordschleife"


class Fault(enum.Enum):
    """The injected faults (front-left travel sensor unless stated;
    :func:`~wheelload.studies.experiments.faults.sensor_faults.inject`)."""

    CLEAN = "clean"
    STUCK = "stuck"  # travel frozen at its value at the onset, its rate 0
    DRIFT = "drift"  # travel drifts by 1 mm/s from the onset
    SPIKES = "spikes"  # single-sample 20 mm spikes on 1 % of samples, random corners
    ACCELERATION_BIAS = "ay-bias"  # lateral acceleration +0.5 m/s^2 from the onset
    TRAVEL_OFFSET = "offset-4mm"  # both front travel sensors read 4 mm high (ride height)


class EstimatorModel(enum.Enum):
    """The estimators' vehicle model: the file's (``full``) or the paper's (``paper``;
    :mod:`~wheelload.studies.experiments.runs.estimator_model`)."""

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
