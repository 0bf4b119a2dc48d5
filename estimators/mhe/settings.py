r"""The MHE's settings: window length, constraint handling, bounds, arrival cost, losses,
bias states and the OSQP settings (Siegloff & Choi eq. 12-17 in a window, Rao, Rawlings &
Lee 2001).

Frozen dataclasses and enums only, no solver: the command line and the studies take
them from :mod:`wheelload.estimators` without importing OSQP.

Example
-------
>>> MheSettings(horizon=10, constraint=Constraint.HARD, bounded=True).label()
'MHE N=10 (hard, bounded)'
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

L1_CORE = 0.05  # σ, width of the quadratic core that realises the L1 loss


class Constraint(enum.Enum):
    """How the equilibrium :math:`A x = b` enters the window."""

    SOFT = "soft"  # penalty weighted by R_c^-1 (eq. 17)
    HARD = "hard"  # equality on every sample


class Loss(enum.Enum):
    """Penalty on one residual group."""

    QUADRATIC = "quadratic"
    HUBER = "huber"
    L1 = "l1"


@dataclass(frozen=True, kw_only=True)
class ResidualLoss:
    """The loss of a residual group; ``threshold`` [σ] is Huber's corner."""

    kind: Loss = Loss.QUADRATIC
    threshold: float = 2.0

    def __post_init__(self) -> None:
        if not isinstance(self.kind, Loss):
            raise TypeError(f"kind must be a Loss, got {self.kind!r}")
        if not (math.isfinite(self.threshold) and self.threshold > 0):
            raise ValueError(f"threshold must be a positive number of sigma, got {self.threshold}")

    @property
    def robust(self) -> bool:
        return self.kind is not Loss.QUADRATIC

    def weights(self) -> tuple[float, float]:
        """(kappa, mu): the cost kappa/2 (rho - e)^2 + mu ``|e|`` that realises the loss."""
        if self.kind is Loss.HUBER:
            return 1.0, self.threshold
        return 1.0 / L1_CORE, 1.0

    def label(self) -> str:
        if self.kind is Loss.HUBER:
            return f"huber {self.threshold:g}σ"
        return self.kind.value


class BiasStates(enum.Flag):
    """Slow sensor errors estimated as states.

    ``TRAVEL`` and ``RIDE_HEIGHT`` exclude each other, as do ``ACCELERATION`` and
    ``LATERAL``. Travel offsets and both accelerometer biases together are five slow
    unknowns against three equilibrium rows: an ay bias and a roll pattern of travel
    offsets leave the same residual. ``RIDE_HEIGHT | LATERAL`` (three unknowns: the
    front and rear ride heights, ay) is observable.
    """

    NONE = 0
    TRAVEL = enum.auto()  # offsets of the four travel sensors [m] (three observable combinations)
    ACCELERATION = enum.auto()  # ax, ay biases [m/s^2]
    RIDE_HEIGHT = enum.auto()  # one offset per axle, both sensors alike [m]
    LATERAL = enum.auto()  # ay bias only [m/s^2]

    def label(self) -> str:
        names = [name for name, flag in (("travel", BiasStates.TRAVEL),
                 ("ride height", BiasStates.RIDE_HEIGHT), ("ax/ay", BiasStates.ACCELERATION),
                 ("ay", BiasStates.LATERAL)) if flag in self]  # fmt: skip
        return "+".join(names) + " bias" if names else ""

    @property
    def travel_states(self) -> int:
        """Number of travel-offset variables."""
        return 3 if BiasStates.TRAVEL in self else 2 if BiasStates.RIDE_HEIGHT in self else 0

    @property
    def acceleration_columns(self) -> list[int]:
        """Columns of (ax, ay) with a bias state."""
        if BiasStates.ACCELERATION in self:
            return [0, 1]
        return [1] if BiasStates.LATERAL in self else []


class Arrival(enum.Enum):
    """Covariance :math:`\\Pi` of the arrival prior."""

    KALMAN = "kalman"  # P_{k-N} + Q from the filter's covariance recursion
    STEADY_STATE = "steady-state"  # the recursion's fixed point at the median interval


@dataclass(frozen=True, kw_only=True)
class SolverSettings:
    """OSQP settings (tolerances in the QP's kN units, cost scaled to unit Hessian diagonal)."""

    eps_abs: float = 1e-6
    eps_rel: float = 1e-6
    max_iter: int = 500
    polish: bool = False
    check_termination: int = 5
    adaptive_rho_interval: int = 25  # fixed, so that Python and generated C iterate alike
    rho: float = 0.1  # initial ADMM step size; adapted during the solves and carried in the state

    def __post_init__(self) -> None:
        if not (self.eps_abs > 0 and self.eps_rel >= 0):
            raise ValueError(f"eps_abs must be > 0 and eps_rel >= 0, got {self}")
        if not self.rho > 0:
            raise ValueError(f"rho must be > 0, got {self.rho}")
        if self.max_iter < 1 or self.check_termination < 1:
            raise ValueError(f"max_iter and check_termination must be >= 1, got {self}")


@dataclass(frozen=True, kw_only=True)
class MheSettings:
    """Window length, constraint handling, bounds and arrival cost of the MHE."""

    horizon: int = 10
    constraint: Constraint = Constraint.SOFT
    bounded: bool = False
    max_load: float = math.inf  # N, upper bound when ``bounded``
    arrival: Arrival = Arrival.KALMAN
    solver: SolverSettings = field(default_factory=SolverSettings)
    suspension_loss: ResidualLoss = field(default_factory=ResidualLoss)
    constraint_loss: ResidualLoss = field(default_factory=ResidualLoss)  # soft only
    bias_states: BiasStates = BiasStates.NONE
    lag: int = 0  # samples: the output is the window's estimate of sample k - lag

    def __post_init__(self) -> None:
        if not isinstance(self.horizon, int) or self.horizon < 1:
            raise ValueError(f"horizon must be an integer >= 1, got {self.horizon!r}")
        if not isinstance(self.constraint, Constraint):
            raise TypeError(f"constraint must be a Constraint, got {self.constraint!r}")
        if not isinstance(self.arrival, Arrival):
            raise TypeError(f"arrival must be an Arrival, got {self.arrival!r}")
        if not self.max_load > 0:
            raise ValueError(f"max_load must be > 0, got {self.max_load}")
        for name in ("suspension_loss", "constraint_loss"):
            if not isinstance(getattr(self, name), ResidualLoss):
                raise TypeError(f"{name} must be a ResidualLoss, got {getattr(self, name)!r}")
        if not isinstance(self.bias_states, BiasStates):
            raise TypeError(f"bias_states must be BiasStates, got {self.bias_states!r}")
        if not isinstance(self.lag, int) or not 0 <= self.lag < self.horizon:
            raise ValueError(f"lag must be an integer in [0, horizon), got {self.lag!r}")
        hard = self.constraint is Constraint.HARD
        both = (
            BiasStates.TRAVEL | BiasStates.RIDE_HEIGHT,
            BiasStates.ACCELERATION | BiasStates.LATERAL,
        )
        if any(pair in self.bias_states for pair in both):
            raise ValueError(
                "bias_states: TRAVEL and RIDE_HEIGHT exclude each other, as do ACCELERATION "
                "and LATERAL"
            )
        if hard and self.bias_states.acceleration_columns:
            raise ValueError(
                "acceleration bias states need the soft constraint (hard: the bounds would "
                "move with the bias); use constraint=Constraint.SOFT"
            )
        if hard and self.constraint_loss.robust:
            raise ValueError("a hard constraint has no residual: constraint_loss must be quadratic")

    @property
    def extended(self) -> bool:
        """True when the window needs auxiliary or bias variables (:mod:`.window`)."""
        return (
            self.suspension_loss.robust
            or self.constraint_loss.robust
            or self.bias_states != BiasStates.NONE
        )

    def label(self) -> str:
        bounds = ", bounded" if self.bounded else ""
        arrival = ", steady arrival" if self.arrival is Arrival.STEADY_STATE else ""
        extra = ""
        if self.suspension_loss.robust:
            extra += f", susp {self.suspension_loss.label()}"
        if self.constraint_loss.robust:
            extra += f", eq {self.constraint_loss.label()}"
        if self.bias_states != BiasStates.NONE:
            extra += f", {self.bias_states.label()}"
        if self.lag:
            extra += f", lag {self.lag}"
        return f"MHE N={self.horizon} ({self.constraint.value}{bounds}{arrival}{extra})"
