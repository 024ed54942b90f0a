"""PDDL names for the scenario's robots and locations that can never collide.

A scenario may call a room ``visited``, ``goto_room`` or ``act-cost``, name two rooms ``A``
and ``a`` (PDDL is case-insensitive), or use characters PDDL does not allow. Every object
therefore gets a name of its own kind: ``rob_`` or ``loc_`` followed by the user's name in
lower case with anything but letters, digits, ``-`` and single ``_`` replaced, and an index
when two user names would still meet. No identifier of tmpnav's domains starts with
``rob_`` or ``loc_`` (``robot_in`` does not: the fourth character is ``o``), so an object
name can never equal a type, predicate, function or action, nor another object.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

ROBOT_PREFIX = "rob_"
LOCATION_PREFIX = "loc_"


def _slug(name: str) -> str:
    slug = re.sub(r"[^a-z0-9-]+", "_", name.lower())
    slug = re.sub(r"_+", "_", slug).strip("_")
    return slug or "x"


def _assign(prefix: str, names: Iterable[str]) -> dict[str, str]:
    out: dict[str, str] = {}
    taken: set[str] = set()
    for i, name in enumerate(dict.fromkeys(names)):
        pddl = prefix + _slug(name)
        if pddl in taken:
            pddl = f"{pddl}-{i}"
        while pddl in taken:  # a user name that already ends in "-<i>"
            pddl += "x"
        taken.add(pddl)
        out[name] = pddl
    return out


@dataclass(frozen=True)
class PddlNames:
    """The PDDL name of every robot and location, and the way back."""

    robot: dict[str, str]
    location: dict[str, str]

    @classmethod
    def of(cls, robots: Iterable[str], locations: Iterable[str]) -> PddlNames:
        return cls(_assign(ROBOT_PREFIX, robots), _assign(LOCATION_PREFIX, locations))

    def robot_named(self, pddl: str) -> str:
        """The robot whose PDDL name is ``pddl`` (KeyError if none)."""
        return self._robots_back[pddl.lower()]

    def location_named(self, pddl: str) -> str:
        """The location whose PDDL name is ``pddl`` (KeyError if none)."""
        return self._locations_back[pddl.lower()]

    @cached_property
    def _robots_back(self) -> dict[str, str]:
        return {v: k for k, v in self.robot.items()}

    @cached_property
    def _locations_back(self) -> dict[str, str]:
        return {v: k for k, v in self.location.items()}
