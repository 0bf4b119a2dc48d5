"""The suspension model under identification: a CasADi Function and its parameter entries.

Every input of the Function named in ``parameters`` is a parameter vector
(entry names given); every other input is a signal (``d``, ``v`` and any
further input the model takes, looked up by name in a log). Regressors are
the Function's Jacobian with respect to the stacked parameters, so a change
of the model in ``wheelload.models`` changes the identification with no
other edit.

Example
-------
>>> model = default_model()
>>> model.signal_inputs()
(('d', 4), ('v', 4))
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from wheelload.models import ModelParameters, suspension_function
from wheelload.models.suspension import (
    piecewise_damper_names,
    piecewise_damper_suspension_function,
)

SEGMENT_SEPARATOR = "_"


@dataclass(frozen=True, kw_only=True, eq=False)
class SuspensionModel:
    """A suspension Function ``z = f(signals..., parameters...)`` and its parameter names."""

    function: ca.Function
    parameters: dict[str, tuple[str, ...]]  # input name -> entry names

    def __post_init__(self) -> None:
        names = [self.function.name_in(i) for i in range(self.function.n_in())]
        for block, entries in self.parameters.items():
            if block not in names:
                raise ValueError(f"model '{self.function.name()}' has no input '{block}'")
            if self.function.size1_in(names.index(block)) != len(entries):
                raise ValueError(f"input '{block}' of '{self.function.name()}' size mismatch")
        if self.function.n_out() < 1 or self.function.size1_out(0) != 4:
            raise ValueError(f"model '{self.function.name()}' must output 4 wheel loads")

    def parameter_names(self) -> tuple[str, ...]:
        """All parameter entries, blocks in input order."""
        return tuple(name for block in self.blocks() for name in self.parameters[block])

    def blocks(self) -> tuple[str, ...]:
        """Parameter inputs in the Function's input order."""
        f = self.function
        return tuple(f.name_in(i) for i in range(f.n_in()) if f.name_in(i) in self.parameters)

    def signal_inputs(self) -> tuple[tuple[str, int], ...]:
        """``(name, size)`` of every non-parameter input, in input order."""
        f = self.function
        return tuple(
            (f.name_in(i), f.size1_in(i))
            for i in range(f.n_in())
            if f.name_in(i) not in self.parameters
        )

    def loads(self, signals: dict[str, ca.SX], theta: ca.SX) -> ca.SX:
        """The model's four loads with signal expressions and the stacked parameters."""
        arguments = dict(signals)
        start = 0
        for block in self.blocks():
            size = len(self.parameters[block])
            arguments[block] = theta[start : start + size]
            start += size
        return self.function.call(arguments)[self.function.name_out(0)]

    def initial_values(self, p: ModelParameters) -> np.ndarray:
        """Stacked parameter values from a vehicle's model parameters.

        An entry named after a model parameter takes its value; a map segment
        ``<name>_<j>`` (piecewise damper) starts from the value of ``<name>``.
        """
        vector = dict(zip(ModelParameters.names(), p.vector()))
        values = []
        for name in self.parameter_names():
            base = base_parameter(name)
            if base not in vector:
                raise ValueError(f"no start value for model parameter '{name}'")
            values.append(vector[base])
        return np.array(values, float)


def base_parameter(name: str) -> str:
    """The model parameter an entry belongs to: ``damper_push_front_1 -> damper_push_front``."""
    head, _, tail = name.rpartition(SEGMENT_SEPARATOR)
    return head if tail.isdigit() and head in ModelParameters.names() else name


def segment_index(name: str) -> int | None:
    """Segment number of a map entry (``_<j>`` suffix), None for a plain parameter."""
    head, _, tail = name.rpartition(SEGMENT_SEPARATOR)
    return int(tail) if tail.isdigit() and head in ModelParameters.names() else None


def default_model() -> SuspensionModel:
    """The bundled suspension model (paper eq. 3-9) with the linear push/pull damper."""
    return SuspensionModel(
        function=suspension_function(), parameters={"p": ModelParameters.names()}
    )


def piecewise_model(knots: tuple[float, ...]) -> SuspensionModel:
    """The suspension model with a piecewise-linear damper map over velocity ``knots`` [m/s].

    Segment ``j`` of ``damper_push_front`` is the entry ``damper_push_front_j``.
    """
    return SuspensionModel(
        function=piecewise_damper_suspension_function(knots),
        parameters={"p": ModelParameters.names(), "damper": piecewise_damper_names(knots)},
    )
