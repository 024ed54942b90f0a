"""A fleet that works: each robot visits at least ``planner.min_rooms`` of the goal rooms.

Neither objective keeps a whole fleet at work. The sum of action costs is least when the
robots nearest the rooms do them all; the makespan counts only the robot that ends last, so
the others may stand at their docks; and the weighted sum of the two pays for every move a
robot whose group ends early makes and gains nothing from it (office, 100 rooms, 16 robots:
7-9 robots on one room or none, benchmarks/README.md). An operator who wants every robot at
work says so: ``planner.min_rooms`` (``--min-rooms``).

A work room is a goal room a robot enters that is not its end (its dock): a room of
``goals.visit`` or one of its own targets. Each robot must enter at least

    need = min(min_rooms, floor(W / R))

of them, W the work rooms no robot starts in (those are visited from the outset) and R the
robots: a minimum the goals cannot give to every robot is lowered to what they can. A plan's
**shortfall** is the sum over the robots of the rooms they lack, and the search ranks a plan
:func:`tmpnav.task.objectives.strict_price` higher per room it lacks (``PlanCost.ranked``): as
much as a conflict left, more than any objective tmpnav meets. So the search keeps to the
minimum wherever a plan that does exists among those it finds, and otherwise ends on the plan
that lacks least, which the report names. Each stage works on the same price:

- OR-Tools' first routes count the work rooms of each route in a dimension whose end has a
  soft lower bound at ``need`` (tmpnav.task.routing);
- the edits between routes are screened with the shortfall priced (tmpnav.task.routes), so an
  edit that hands rooms to a robot short of them is costed first;
- every plan the search costs is ranked with it (tmpnav.task.search).

The exact searches do not take a minimum: a run with one plans with the anytime search.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from tmpnav.types import Goals


def work_rooms(goals: Goals) -> frozenset[str]:
    """The rooms that count as work: those of ``goals.visit`` and the robots' targets (not their ends)."""
    return frozenset(goals.visit) | frozenset(x for _, rooms in goals.per_robot for x in rooms)


def need(goals: Goals, starts: Mapping[str, str], min_rooms: int) -> int:
    """The work rooms each robot must enter: ``min_rooms``, at most the share per robot of the
    work rooms that none of the robots (``starts``: robot -> where it starts) starts in."""
    if min_rooms <= 0 or not starts:
        return 0
    return min(min_rooms, len(work_rooms(goals) - set(starts.values())) // len(starts))


def counts(steps: Iterable[Iterable[tuple[str, ...]]], work: frozenset[str]) -> dict[str, int]:
    """The work rooms each robot enters in ``steps``: steps of moves whose first item is the
    robot and last the room it enters ((robot, origin, target) or (robot, target))."""
    found: dict[str, int] = {}
    for step in steps:
        for move in step:
            if move[-1] in work:
                found[move[0]] = found.get(move[0], 0) + 1
    return found


def shortfall(entered: Mapping[str, int], robots: Sequence[str], least: int) -> int:
    """The rooms the ``robots`` lack of ``least`` each, having ``entered`` so many."""
    return sum(max(least - entered.get(r, 0), 0) for r in robots) if least > 0 else 0
