"""Quantities in scenario files: plain numbers in the documented unit, or strings with a unit."""

from __future__ import annotations

import math

import pytest

from tmpnav.scenario.units import UNITS, UnitError, parse_quantity, si_unit


@pytest.mark.parametrize(
    ("value", "dimension", "expected"),
    [
        (1.5, "length", 1.5),  # a plain number is read in the SI unit
        (3, "time", 3.0),
        ("40 cm", "length", 0.40),
        ("40cm", "length", 0.40),  # the space is optional
        ("  2.5 mm ", "length", 0.0025),
        ("90 deg", "angle", math.pi / 2),
        ("-90 deg", "angle", -math.pi / 2),
        ("1.5e2 ms", "time", 0.15),
        (".5 m/s", "speed", 0.5),
        ("50 cm/s", "speed", 0.5),
        ("180 deg/s", "angular_speed", math.pi),
        ("+1 rad", "angle", 1.0),
        (7, None, 7.0),  # dimensionless
    ],
)
def test_quantities_convert_to_si(value: object, dimension: str | None, expected: float) -> None:
    assert parse_quantity(value, dimension) == pytest.approx(expected)


@pytest.mark.parametrize(
    ("value", "dimension", "fragment"),
    [
        ("3 kg", "speed", "has unit 'kg', which is not a unit of speed (m/s, cm/s)"),
        ("30 deg", "length", "has unit 'deg', which is not a unit of length (m, cm, mm)"),  # an angle for a length
        ("2 m", "angle", "which is not a unit of angle (rad, deg)"),
        ("3 m", None, "has a unit 'm' but is a plain number"),
        ("fast", "speed", "is not a number"),
        ("1.5.2 m", "length", "is not a number"),
        ("", "length", "is not a number"),
        (True, "length", "is a boolean"),  # YAML `true` is not 1 m
        (None, "length", "is a NoneType"),
        ([1, 2], "length", "is a list"),
    ],
)
def test_bad_quantities_say_what_is_wrong(value: object, dimension: str | None, fragment: str) -> None:
    with pytest.raises(UnitError) as info:
        parse_quantity(value, dimension)
    assert fragment in str(info.value)


def test_nan_and_inf_pass_through_for_the_schema_to_reject() -> None:
    # parse_quantity converts; Number and Vector in the schema report non-finite values
    assert math.isnan(parse_quantity(float("nan"), "length"))
    assert parse_quantity(float("-inf"), "length") == -math.inf


def test_the_documented_unit_comes_first() -> None:
    assert [si_unit(d) for d in UNITS] == ["m", "rad", "s", "m/s", "rad/s"]
    assert si_unit(None) == ""
    for factors in UNITS.values():
        assert next(iter(factors.values())) == 1.0  # the first unit is the SI one
