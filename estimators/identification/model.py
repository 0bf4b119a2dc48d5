"""The suspension model under identification: a CasADi Function and the meaning of its inputs.

Every input of the Function is one of: a parameter vector (``parameters``:
entry names, the things fitted), a signal (``channels``: one log channel
name per entry, e.g. ``d_fl``), or a constant (``constants``: numbers held
fixed, e.g. term switches). Regressors are the Function's Jacobian with
respect to the stacked parameters, and rigs and logs fill the signal entries
by channel name, so a model change in ``wheelload.models`` (a new term, a
new parameter, a stacked input vector) changes the identification with no
edit here beyond describing the inputs in :func:`default_model`.

Example
-------
>>> model = default_model()
>>> model.channel_names()[:2]
('d_fl', 'd_fr')
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from wheelload.models import GATES, ModelParameters, gates_function, suspension_function
from wheelload.models.conventions import WHEELS
from wheelload.models.inputs import INPUTS, OPTIONAL_INPUTS
from wheelload.models.suspension.pseudo_measurement import (
    piecewise_damper_names,
    piecewise_damper_suspension_function,
)

SEGMENT_SEPARATOR = "_"

TRAVEL = tuple(f"d_{w}" for w in WHEELS)
TRAVEL_RATE = tuple(f"v_{w}" for w in WHEELS)


@dataclass(frozen=True, kw_only=True, eq=False)
class SuspensionFitModel:
    """A suspension Function ``z[4] = f(inputs...)`` and what each of its inputs is."""

    function: ca.Function
    parameters: dict[str, tuple[str, ...]]  # input name -> parameter entry names
    channels: dict[str, tuple[str, ...]]  # input name -> log channel name per entry
    constants: dict[str, tuple[float, ...]] = field(default_factory=dict)  # input -> values
    optional: frozenset[str] = frozenset()  # channels a log may lack (taken as 0)
    held: frozenset[str] = frozenset()  # parameter entries never fitted (body, not suspension)

    def __post_init__(self) -> None:
        f = self.function
        for i in range(f.n_in()):
            name, size = f.name_in(i), f.size1_in(i)
            kinds = [
                table[name]
                for table in (self.parameters, self.channels, self.constants)
                if name in table
            ]
            if len(kinds) != 1:
                raise ValueError(
                    f"model '{f.name()}': input '{name}' must be exactly one of parameters, "
                    "channels or constants"
                )
            if len(kinds[0]) != size:
                raise ValueError(f"model '{f.name()}': input '{name}' has {size} entries")
        if f.n_out() < 1 or f.size1_out(0) != 4:
            raise ValueError(f"model '{f.name()}' must output 4 wheel loads")

    def _inputs(self, table: dict) -> tuple[str, ...]:
        f = self.function
        return tuple(f.name_in(i) for i in range(f.n_in()) if f.name_in(i) in table)

    def blocks(self) -> tuple[str, ...]:
        """Parameter inputs in the Function's input order."""
        return self._inputs(self.parameters)

    def parameter_names(self) -> tuple[str, ...]:
        """All parameter entries, blocks in input order."""
        return tuple(name for block in self.blocks() for name in self.parameters[block])

    def channel_names(self) -> tuple[str, ...]:
        """All signal entries (log channel names), inputs in order."""
        return tuple(n for block in self._inputs(self.channels) for n in self.channels[block])

    def loads(self, channels: dict[str, ca.SX], theta: ca.SX) -> ca.SX:
        """The four loads with an expression per channel (missing channels: 0) and the
        stacked parameters ``theta``."""
        unknown = sorted(set(channels) - set(self.channel_names()))
        if unknown:
            raise ValueError(f"model '{self.function.name()}' has no signal '{unknown[0]}'")
        arguments = {}
        for block, names in self.channels.items():
            arguments[block] = ca.vertcat(*[channels[n] if n in channels else 0 for n in names])
        for block, values in self.constants.items():
            arguments[block] = ca.DM(list(values))
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


#: Entries of ``ModelParameters`` that describe the body, the aerodynamics, the
#: tyres, the IMU or the term switches, not the suspension: the model terms
#: make some of them visible in the suspension rows (the mass in the link
#: loads), but they are weighed or measured, not identified here.
HELD = frozenset(
    name
    for name in ModelParameters.names()
    if not name.startswith(
        ("spring_", "damper_", "arb_", "static_", "roll_centre_", "anti_", "bump_gap_",
         "rebound_gap_", "stop_", "unsprung_")
    )
)  # fmt: skip


def model_gates(p: ModelParameters, absent: frozenset[str] = frozenset()) -> tuple[float, ...]:
    """Term gates (``wheelload.models.GATES``) of the vehicle's [model] switches.

    Every input is taken as present except ``absent`` (e.g. the hub
    accelerometers of a log that lacks them, whose terms are then off); the
    road-frame attitude is off (see the comment below).
    """
    valid = np.array([0.0 if name in absent else 1.0 for name in INPUTS])
    gates = np.asarray(gates_function()(valid, p.vector())[0]).ravel()
    # The road-frame attitude takes the tyre deflection (k d / k_t) into the
    # rotation of the specific force that drives the link loads: the springs and
    # bars would enter nonlinearly and be held. Its effect on the suspension rows
    # is second order (angle x specific force), so the fit leaves it off.
    gates[GATES.index("road_frame")] = 0.0
    return tuple(float(g) for g in gates)


#: The paper's model: every term gate off.
PAPER_GATES = (0.0,) * len(GATES)


def default_model(gates: tuple[float, ...] = PAPER_GATES) -> SuspensionFitModel:
    """The bundled suspension model with the linear push/pull damper.

    ``gates`` (constants, :func:`model_gates`) switch the terms beyond the
    paper's eq. 3-9; by default they are off.
    """
    return SuspensionFitModel(
        function=suspension_function(),
        parameters={"p": ModelParameters.names()},
        channels={"u": INPUTS},
        constants={"gates": tuple(gates)},
        optional=frozenset(OPTIONAL_INPUTS),
        held=HELD,
    )


def piecewise_model(
    knots: tuple[float, ...], gates: tuple[float, ...] = PAPER_GATES
) -> SuspensionFitModel:
    """The suspension model with a piecewise-linear damper map over velocity ``knots`` [m/s].

    Segment ``j`` of ``damper_push_front`` is the entry ``damper_push_front_j``.
    """
    return SuspensionFitModel(
        function=piecewise_damper_suspension_function(knots),
        parameters={"p": ModelParameters.names(), "damper": piecewise_damper_names(knots)},
        channels={"u": INPUTS},
        constants={"gates": tuple(gates)},
        optional=frozenset(OPTIONAL_INPUTS),
        held=HELD,
    )
