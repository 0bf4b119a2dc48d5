"""The vehicle model a family method is built on: ``--suspension full|paper``.

An enum and its default only (no numerics), so that a command's ``--help`` offers the
choices at once; :mod:`~wheelload.estimators.protocol` hands them out with the protocol.
"""

from __future__ import annotations

import enum


class SuspensionModel(enum.Enum):
    """The vehicle model of a family method (:mod:`wheelload.estimators.family.suspension_model`).

    ``FULL``: the KF's own suspension pseudo-measurement and equilibrium with every
    term the vehicle file switches on; ``PAPER``: the papers' bare eq. 9 and eq. 15-16.
    """

    FULL = "full"  # the KF's model, every term the vehicle file switches on
    PAPER = "paper"  # the papers' bare eq. 9 and eq. 15-16

    @classmethod
    def parse(cls, text: str) -> SuspensionModel:
        """``"full"`` or ``"paper"`` (command line); anything else names the choices."""
        for member in cls:
            if member.value == text:
                return member
        raise ValueError(f"unknown suspension model {text!r}; choose 'full' or 'paper'")


#: A fair comparison: every method on the KF's own model.
DEFAULT_MODEL = SuspensionModel.FULL
