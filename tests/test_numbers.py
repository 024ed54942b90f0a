"""Figures as the terminal prints them: bounds, lengths, angles, NEES and shares, each with no
more precision than the models have and words where a number would mislead."""

from __future__ import annotations

import doctest
import math
from collections.abc import Callable

import pytest

from tmpnav import numbers
from tmpnav.numbers import angle, length, nees, percent, probability


def test_the_docstrings_examples_hold() -> None:
    failed, tried = doctest.testmod(numbers)
    assert tried >= 5 and failed == 0


@pytest.mark.parametrize(
    ("p", "text"),
    [
        (6.5e-300, "< 1e-6"),
        (0.0, "< 1e-6"),
        (-1e-12, "< 1e-6"),  # a bound that rounding put below zero
        (9.9e-7, "< 1e-6"),
        (1e-6, "1e-6"),
        (3.44e-4, "3.4e-4"),
        (9.96e-4, "1e-3"),
        (1.2e-3, "0.0012"),
        (0.0123, "0.012"),
        (0.05, "0.05"),
        (0.456, "0.46"),
        (0.994, "0.99"),
        (0.9996, "> 0.99"),
        (1.0, "1"),
        (2.5, "1"),  # a union bound past 1 says no more than 1
        (math.inf, "1"),
        (math.nan, "n/a"),
    ],
)
def test_probability(p: float, text: str) -> None:
    assert probability(p) == text


@pytest.mark.parametrize(
    ("m", "text"),
    [
        (0.005, "0.5 cm"),
        (0.041, "4.1 cm"),
        (0.0996, "10.0 cm"),
        (0.1, "0.10 m"),
        (0.234, "0.23 m"),
        (12.0, "12.00 m"),
        (0.00099, "< 0.1 cm"),
        (0.001, "0.1 cm"),
        (0.0, "< 0.1 cm"),
        (-0.02, "-2.0 cm"),
        (math.inf, "unbounded"),
        (math.nan, "n/a"),
    ],
)
def test_length(m: float, text: str) -> None:
    assert length(m) == text


@pytest.mark.parametrize(
    ("rad", "text"),
    [
        (0.0, "< 0.1 deg"),
        (math.radians(0.09), "< 0.1 deg"),
        (math.radians(0.1), "0.1 deg"),
        (math.radians(6.44), "6.4 deg"),
        (math.pi, "180.0 deg"),
        (-math.radians(2.0), "-2.0 deg"),
        (math.inf, "unbounded"),
        (math.nan, "n/a"),
    ],
)
def test_angle(rad: float, text: str) -> None:
    assert angle(rad) == text


@pytest.mark.parametrize(
    ("x", "text"),
    [(2.04, "2.0"), (2.17, "2.2"), (13.26, "13.3"), (0.01, "< 0.1"), (math.inf, "unbounded"), (math.nan, "n/a")],
)
def test_nees(x: float, text: str) -> None:
    assert nees(x) == text


@pytest.mark.parametrize(
    ("share", "text"),
    [
        (0.0, "0%"),
        (0.0004, "< 0.1%"),
        (0.0042, "0.4%"),
        (0.2478, "24.8%"),
        (0.9996, "> 99.9%"),
        (1.0, "100%"),
        (1.5, "150.0%"),
        (-0.1, "-10.0%"),
        (math.inf, "unbounded"),
        (math.nan, "n/a"),
    ],
)
def test_percent(share: float, text: str) -> None:
    assert percent(share) == text


@pytest.mark.parametrize("f", [probability, length, angle, nees, percent])
def test_never_a_bare_nan_or_inf(f: Callable[[float], str]) -> None:
    for x in (math.nan, math.inf, -math.inf):
        text = f(x)
        assert "nan" not in text and "inf" not in text, (f, x, text)
