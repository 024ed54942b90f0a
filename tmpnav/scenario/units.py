"""Physical quantities in scenario files.

A value is either a plain number, read in the key's documented unit (also when quoted,
``"1e-3"``), or a string with an explicit unit such as ``"90 deg"``, ``"40 cm"`` or
``"0.5 m/s"``. Everything is converted
to SI (metres, radians, seconds) on loading.
"""

from __future__ import annotations

import math
import re

#: dimension -> {unit: factor to the SI unit}; the first unit is the one documented.
UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 0.01, "mm": 0.001},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "time": {"s": 1.0, "ms": 0.001},
    "speed": {"m/s": 1.0, "cm/s": 0.01},
    "angular_speed": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/]+)?\s*$")


class UnitError(ValueError):
    """A value that is not a number or a number with a unit of the right dimension."""


def si_unit(dimension: str | None) -> str:
    """The unit a plain number is read in, for messages and the reference table."""
    if dimension is None:
        return ""
    return next(iter(UNITS[dimension]))


def parse_quantity(value: object, dimension: str | None) -> float:
    """Convert ``value`` to a float in SI units.

    ``dimension`` None means a dimensionless number (a string with a unit is rejected).
    Booleans are rejected although Python treats them as integers: ``true`` for a
    distance is a mistake in a scenario file.
    """
    if isinstance(value, bool):
        raise UnitError("is a boolean")
    if isinstance(value, (int, float)):
        try:
            return float(value)
        except OverflowError:  # an integer beyond the largest float
            return math.inf if value > 0 else -math.inf
    if isinstance(value, str):
        match = _QUANTITY.match(value)
        if match is None:
            raise UnitError("is not a number")
        number, unit = float(match.group(1)), match.group(2)
        if unit is None:  # a quoted number, '1e-3': read in the documented unit
            return number
        if dimension is None:
            raise UnitError(f"has a unit '{unit}' but is a plain number")
        factors = UNITS[dimension]
        if unit not in factors:
            known = ", ".join(factors)
            raise UnitError(f"has unit '{unit}', which is not a unit of {dimension.replace('_', ' ')} ({known})")
        return number * factors[unit]
    raise UnitError(f"is a {type(value).__name__}")
