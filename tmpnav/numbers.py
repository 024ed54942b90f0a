"""Figures as the terminal prints them: no more precision than the models have, units that suit
the size, and words where a number would mislead.

Every printer of a probability, an uncertainty, a NEES or a share goes through these functions,
so that ``tmpnav plan``, ``replan``, ``simulate`` and their warnings read alike. plan.json and
the CSV files keep the numbers as they are. Each function prints ``n/a`` for nan (nothing to
measure); what infinity reads as depends on the figure and is said in its docstring.
"""

from __future__ import annotations

import math

#: below this a probability is printed as "< 1e-6": the models' own errors are larger
PROBABILITY_FLOOR = 1e-6
#: lengths below this (m) are printed in cm
CM_BELOW = 0.1


def probability(p: float) -> str:
    """A probability or a bound on one, with 2 significant digits.

    Below 1e-6 (0 included) it reads ``< 1e-6``; below 1e-3 in scientific notation with a
    one-digit exponent; from 0.995 ``> 0.99``; 1 or more (a union bound can pass 1; infinity too)
    reads ``1``: the bound says nothing then. nan reads ``n/a``.

    >>> [probability(p) for p in (6.5e-300, 0.0, 3.4e-4, 0.0123, 0.05, 0.456, 1.7, math.nan)]
    ['< 1e-6', '< 1e-6', '3.4e-4', '0.012', '0.05', '0.46', '1', 'n/a']
    """
    if math.isnan(p):
        return "n/a"
    if p < PROBABILITY_FLOOR:
        return f"< {PROBABILITY_FLOOR:.0e}".replace("e-0", "e-")
    if p >= 1.0:
        return "1"
    if p >= 0.995:  # not rounded up to 1, which only a bound that says nothing reads
        return "> 0.99"
    if p < 1e-3:
        mantissa, exponent = f"{p:.1e}".split("e")
        return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"
    return f"{p:.2g}"


def length(m: float) -> str:
    """A standard deviation, an error, a spread or a distance between uncertain positions.

    Below 0.1 m in cm with one decimal (below 0.1 cm: ``< 0.1 cm``), from 0.1 m in m with two
    decimals; a negative length keeps its sign. nan reads ``n/a``, infinity ``unbounded``.

    >>> [length(x) for x in (0.005, 0.041, 0.0004, 0.0, 0.234, 3.0, -0.02, math.inf, math.nan)]
    ['0.5 cm', '4.1 cm', '< 0.1 cm', '< 0.1 cm', '0.23 m', '3.00 m', '-2.0 cm', 'unbounded', 'n/a']
    """
    if math.isnan(m):
        return "n/a"
    if math.isinf(m):
        return "unbounded" if m > 0 else "-unbounded"
    if m < 0:
        return "-" + length(-m)
    if m >= CM_BELOW:
        return f"{m:.2f} m"
    cm = 100.0 * m
    return "< 0.1 cm" if cm < 0.1 else f"{cm:.1f} cm"


def angle(rad: float) -> str:
    """An angle, such as a heading's standard deviation, in degrees with one decimal.

    Below 0.1 deg it reads ``< 0.1 deg``; a negative angle keeps its sign. nan reads ``n/a``,
    infinity ``unbounded``.

    >>> [angle(x) for x in (0.0, 1e-4, 0.0401, math.pi, math.inf, math.nan)]
    ['< 0.1 deg', '< 0.1 deg', '2.3 deg', '180.0 deg', 'unbounded', 'n/a']
    """
    if math.isnan(rad):
        return "n/a"
    if math.isinf(rad):
        return "unbounded" if rad > 0 else "-unbounded"
    if rad < 0:
        return "-" + angle(-rad)
    deg = math.degrees(rad)
    return "< 0.1 deg" if deg < 0.1 else f"{deg:.1f} deg"


def nees(x: float) -> str:
    """A normalised estimation error squared (2 for a consistent position estimate), with one
    decimal; below 0.1 it reads ``< 0.1``. nan (no sample) reads ``n/a``, infinity (an error
    against a covariance that allows none) ``unbounded``.

    >>> [nees(x) for x in (2.04, 13.26, 0.01, math.inf, math.nan)]
    ['2.0', '13.3', '< 0.1', 'unbounded', 'n/a']
    """
    if math.isnan(x):
        return "n/a"
    if math.isinf(x):
        return "unbounded"
    return "< 0.1" if 0 <= x < 0.1 else f"{x:.1f}"


def percent(share: float) -> str:
    """A share (0 to 1) as a percentage with at most one decimal.

    Exactly 0 and 1 read ``0%`` and ``100%``; a share that one decimal would round to either
    reads ``< 0.1%`` or ``> 99.9%``; past 1 (a gap relative to a cost) it is printed as it is, a
    negative share keeps its sign. nan reads ``n/a``, infinity ``unbounded``.

    >>> [percent(s) for s in (0.0, 0.0004, 0.0042, 0.5, 0.9996, 1.0, 1.5, math.inf, math.nan)]
    ['0%', '< 0.1%', '0.4%', '50.0%', '> 99.9%', '100%', '150.0%', 'unbounded', 'n/a']
    """
    if math.isnan(share):
        return "n/a"
    if math.isinf(share):
        return "unbounded" if share > 0 else "-unbounded"
    if share < 0:
        return "-" + percent(-share)
    if share == 0.0:
        return "0%"
    if share == 1.0:
        return "100%"
    if share < 0.0005:
        return "< 0.1%"
    if 0.9995 <= share < 1.0:
        return "> 99.9%"
    return f"{100.0 * share:.1f}%"
