"""Every unit of the readers' table against its published definition.

The factors below are built from the definitions, not copied from the table: the SI
prefixes; the inch of the 1959 international yard and pound agreement (0.0254 m exactly)
and the international mile (5280 ft = 1609.344 m, NIST SP 811 B.8); the hour (3600 s) and
the minute (60 s); standard gravity g_n = 9.80665 m/s^2 (3rd CGPM, 1901); the degree
pi/180 rad; one revolution 2 pi rad. Tolerance 1e-15 relative: each side is at most a
few double-precision operations on exact decimal definitions.
"""

import math

import pytest

from wheelload.estimators.logs.readers.units import UNITS, Kind, UnitError, unit_factor

INCH = 0.0254
MILE = 5280 * 12 * INCH
HOUR, MINUTE = 3600.0, 60.0
STANDARD_GRAVITY = 9.80665
DEGREE = math.pi / 180.0
REVOLUTION = 2.0 * math.pi

DEFINITIONS = {
    "s": (Kind.TIME, 1.0),
    "sec": (Kind.TIME, 1.0),
    "ms": (Kind.TIME, 1e-3),
    "us": (Kind.TIME, 1e-6),
    "ns": (Kind.TIME, 1e-9),
    "m": (Kind.LENGTH, 1.0),
    "cm": (Kind.LENGTH, 1e-2),
    "mm": (Kind.LENGTH, 1e-3),
    "um": (Kind.LENGTH, 1e-6),
    "in": (Kind.LENGTH, INCH),
    "m/s": (Kind.SPEED, 1.0),
    "mm/s": (Kind.SPEED, 1e-3),
    "km/h": (Kind.SPEED, 1000.0 / HOUR),
    "kph": (Kind.SPEED, 1000.0 / HOUR),
    "mph": (Kind.SPEED, MILE / HOUR),
    "m/s^2": (Kind.ACCELERATION, 1.0),
    "m/s2": (Kind.ACCELERATION, 1.0),
    "m/s²": (Kind.ACCELERATION, 1.0),
    "g": (Kind.ACCELERATION, STANDARD_GRAVITY),
    "G": (Kind.ACCELERATION, STANDARD_GRAVITY),
    "rad/s": (Kind.ANGULAR_RATE, 1.0),
    "deg/s": (Kind.ANGULAR_RATE, DEGREE),
    "°/s": (Kind.ANGULAR_RATE, DEGREE),
    "N": (Kind.FORCE, 1.0),
    "kN": (Kind.FORCE, 1e3),
    "N m": (Kind.TORQUE, 1.0),
    "Nm": (Kind.TORQUE, 1.0),
    "N*m": (Kind.TORQUE, 1.0),
    "kN m": (Kind.TORQUE, 1e3),
    "kNm": (Kind.TORQUE, 1e3),
    "rad": (Kind.ANGLE, 1.0),
    "deg": (Kind.ANGLE, DEGREE),
    "°": (Kind.ANGLE, DEGREE),
    "rpm": (Kind.ROTATION_SPEED, REVOLUTION / MINUTE),
    "1/min": (Kind.ROTATION_SPEED, REVOLUTION / MINUTE),
    "rad/s_wheel": (Kind.ROTATION_SPEED, 1.0),
}


def test_every_unit_has_a_published_definition():
    assert set(UNITS) == set(DEFINITIONS)


@pytest.mark.parametrize("unit", sorted(DEFINITIONS))
def test_unit_factor_equals_its_definition(unit):
    kind, factor = DEFINITIONS[unit]
    assert unit_factor(unit, kind, "channels.x") == pytest.approx(factor, rel=1e-15, abs=0)


def test_spot_values_a_driver_knows():
    # 60 mph is 96.56 km/h; 1 g on a 1500 kg car is 14.7 kN.
    mph, kmh = (unit_factor(u, Kind.SPEED, "vx") for u in ("mph", "km/h"))
    assert 60.0 * mph / kmh == pytest.approx(96.56064, rel=1e-12)
    assert 1500.0 * unit_factor("g", Kind.ACCELERATION, "az") == pytest.approx(14709.975)


def test_a_unit_of_the_wrong_kind_is_refused_with_the_channel():
    with pytest.raises(UnitError, match=r"channels.vx: unit 'mm' is a length.*speed \(m/s\)"):
        unit_factor("mm", Kind.SPEED, "channels.vx")
    with pytest.raises(UnitError, match=r"channels.ax: unknown unit 'furlong'"):
        unit_factor("furlong", Kind.ACCELERATION, "channels.ax")
