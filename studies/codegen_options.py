"""What ``wheelload codegen``'s arguments mean: one estimator's options with their defaults
(another's refused), the nominal interval under its one name (``--interval``; ``--sample-interval``
and ``--dt`` deprecated), and the MHE's settings from its options."""

from __future__ import annotations

import argparse
import sys

from wheelload.estimators import (
    Arrival,
    BiasStates,
    Constraint,
    Loss,
    MheSettings,
    ResidualLoss,
)
from wheelload.estimators.codegen.kf import CodegenOptions

#: The nominal sample interval's option, and its deprecated spellings (kf, mhe).
INTERVAL_OPTION = "--interval"
DEPRECATED_INTERVAL = ("--sample-interval", "--dt")
#: ``--bias-states`` choices.
BIAS_CHOICES = {
    "none": BiasStates.NONE,
    "travel": BiasStates.TRAVEL,
    "acceleration": BiasStates.ACCELERATION,
    "travel+acceleration": BiasStates.TRAVEL | BiasStates.ACCELERATION,
    "ride-height": BiasStates.RIDE_HEIGHT,
    "ay": BiasStates.LATERAL,
    "ride-height+ay": BiasStates.RIDE_HEIGHT | BiasStates.LATERAL,
    "travel+ay": BiasStates.TRAVEL | BiasStates.LATERAL,
    "ride-height+acceleration": BiasStates.RIDE_HEIGHT | BiasStates.ACCELERATION,
}


def own_options(args: argparse.Namespace, own: dict, other: dict, estimator: str) -> dict:
    """The estimator's options with defaults filled in; another estimator's is an error."""
    foreign = [f"--{name.replace('_', '-')}" for name in other if getattr(args, name) is not None]
    if foreign:
        raise ValueError(f"{', '.join(foreign)}: not an option of --estimator {estimator}")
    return {name: default if getattr(args, name) is None else getattr(args, name)
            for name, default in own.items()}  # fmt: skip


def interval(args: argparse.Namespace) -> float:
    """``--interval``, or a deprecated spelling of it (said on stderr); two different values
    are an error."""
    given = {INTERVAL_OPTION: args.interval}
    for alias in DEPRECATED_INTERVAL:
        value = getattr(args, f"deprecated_{alias[2:].replace('-', '_')}")
        if value is not None:
            print(f"wheelload codegen: {alias} is deprecated: use {INTERVAL_OPTION}",
                  file=sys.stderr)  # fmt: skip
            given[alias] = value
    values = {name: value for name, value in given.items() if value is not None}
    if len(set(values.values())) > 1:
        raise ValueError(
            f"{' and '.join(values)} give different intervals: give {INTERVAL_OPTION} only"
        )
    return next(iter(values.values()), CodegenOptions().sample_interval)


def mhe_settings(values: dict) -> MheSettings:
    """The embedded MHE's settings from ``codegen``'s MHE options (defaults filled in)."""
    threshold = values["huber_threshold"]
    return MheSettings(
        horizon=values["horizon"],
        constraint=Constraint(values["constraint"]),
        bounded=values["bounded"],
        suspension_loss=ResidualLoss(kind=Loss(values["suspension_loss"]), threshold=threshold),
        constraint_loss=ResidualLoss(kind=Loss(values["constraint_loss"]), threshold=threshold),
        bias_states=BIAS_CHOICES[values["bias_states"]],
        lag=values["lag"],
        arrival=Arrival(values["arrival"]),
    )
