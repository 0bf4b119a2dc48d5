"""Unit strings of logged channels and their factors to SI, by kind of quantity.

A small explicit table rather than a general units library: log channels use a
handful of units, and some of their usual spellings mean something else to a
general library (``g`` is the gram in pint; here it is standard gravity, the
unit of an accelerometer). A unit string that is not in the table, or that is
of the wrong kind for the channel, is an error: it is never guessed.

``rpm`` of a wheel speed needs the rolling radius and the ratio of the
measured shaft to the wheel (``v = rpm \\cdot 2\\pi/60 \\cdot r / ratio``);
that conversion is done by the channel map, which carries both.
"""

from __future__ import annotations

import enum
import math

from wheelload.models.conventions import GRAVITY


class Kind(enum.Enum):
    """Physical kind of a channel; each has its SI unit."""

    TIME = "s"
    LENGTH = "m"
    SPEED = "m/s"
    ACCELERATION = "m/s^2"
    ANGULAR_RATE = "rad/s"
    FORCE = "N"
    TORQUE = "N m"
    ANGLE = "rad"
    ROTATION_SPEED = "rpm"  # wheel speed as shaft rotation; needs radius and ratio


#: unit string -> (kind, factor to the SI unit of the kind)
UNITS: dict[str, tuple[Kind, float]] = {
    "s": (Kind.TIME, 1.0),
    "sec": (Kind.TIME, 1.0),
    "ms": (Kind.TIME, 1e-3),
    "us": (Kind.TIME, 1e-6),
    "ns": (Kind.TIME, 1e-9),
    "m": (Kind.LENGTH, 1.0),
    "cm": (Kind.LENGTH, 1e-2),
    "mm": (Kind.LENGTH, 1e-3),
    "um": (Kind.LENGTH, 1e-6),
    "in": (Kind.LENGTH, 0.0254),
    "m/s": (Kind.SPEED, 1.0),
    "mm/s": (Kind.SPEED, 1e-3),
    "km/h": (Kind.SPEED, 1.0 / 3.6),
    "kph": (Kind.SPEED, 1.0 / 3.6),
    "mph": (Kind.SPEED, 0.44704),
    "m/s^2": (Kind.ACCELERATION, 1.0),
    "m/s2": (Kind.ACCELERATION, 1.0),
    "m/s²": (Kind.ACCELERATION, 1.0),
    "g": (Kind.ACCELERATION, GRAVITY),  # standard gravity, not the gram
    "G": (Kind.ACCELERATION, GRAVITY),  # as AiM and MoTeC exports spell it
    "rad/s": (Kind.ANGULAR_RATE, 1.0),
    "deg/s": (Kind.ANGULAR_RATE, math.pi / 180.0),
    "°/s": (Kind.ANGULAR_RATE, math.pi / 180.0),
    "N": (Kind.FORCE, 1.0),
    "kN": (Kind.FORCE, 1e3),
    "N m": (Kind.TORQUE, 1.0),
    "Nm": (Kind.TORQUE, 1.0),
    "N*m": (Kind.TORQUE, 1.0),
    "kN m": (Kind.TORQUE, 1e3),
    "kNm": (Kind.TORQUE, 1e3),
    "rad": (Kind.ANGLE, 1.0),
    "deg": (Kind.ANGLE, math.pi / 180.0),
    "°": (Kind.ANGLE, math.pi / 180.0),
    "rpm": (Kind.ROTATION_SPEED, 2.0 * math.pi / 60.0),  # to rad/s
    "1/min": (Kind.ROTATION_SPEED, 2.0 * math.pi / 60.0),
    "rad/s_wheel": (Kind.ROTATION_SPEED, 1.0),
}


class UnitError(ValueError):
    """A unit string that is unknown or of the wrong kind."""


def unit_factor(unit: str, kind: Kind, where: str) -> float:
    """Factor that converts values in ``unit`` to the SI unit of ``kind``.

    A wheel speed (``Kind.SPEED``) may be given as a rotation speed; the
    factor is then to rad/s and the caller applies radius and ratio. An angular rate may
    be given as a rotation speed (a wheel spin in rpm), the factor to rad/s.
    """
    if unit.strip() not in UNITS:
        raise UnitError(f"{where}: unknown unit '{unit}'; known: {', '.join(sorted(UNITS))}")
    found, factor = UNITS[unit.strip()]
    if found is kind or (kind in (Kind.SPEED, Kind.ANGULAR_RATE) and found is Kind.ROTATION_SPEED):
        return factor
    raise UnitError(
        f"{where}: unit '{unit}' is a {found.name.lower().replace('_', ' ')}, "
        f"the channel needs a {kind.name.lower().replace('_', ' ')} ({kind.value})"
    )
