"""Where the chance constraint splits a fleet: the goal rooms each robot reaches within it.

A move whose collision bound is over the chance constraint costs its penalty
(:func:`tmpnav.types.risk_penalty`), so a plan takes one only where no plan can do without. From
its start, a robot reaches within the constraint the rooms joined to it by moves of the cost
table that carry no penalty. Where these sets split the goal rooms into groups that different
robots reach, work cannot pass from one group to another: the makespan is that of the busiest
group, however many robots stand idle in the others, and an objective that prices the moves
(``weighted``, and ``makespan`` between plans as fast) leaves them idle rather than pay for moves
that end no sooner. The warning names the groups and the robots idle for most of the plan.

The table is the one the planner saw (:attr:`tmpnav.results.PlanReport.table`): with the anytime
search, the moves it asked for, so a group is what the search could reach; a plan remembered from
the cache directory comes with its own moves only, and then says nothing of the groups. Where the
idle robots do not reach the busiest group's rooms even over the constraint (their jobs, or moves
the table does not hold, keep them out), the constraint is not the cause, and no warning is given.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from tmpnav.types import PENALISED, CostTable

#: warn about robots idle for more than this share of the makespan
IDLE_SHARE = 0.5
#: rooms named in a group of the message at most (the rest counted)
NAMED = 4


@dataclass(frozen=True)
class Group:
    """Goal rooms that exactly these robots reach within the chance constraint."""

    rooms: tuple[str, ...]
    robots: tuple[str, ...]


def reach_groups(table: CostTable, rooms: Iterable[str]) -> list[Group]:
    """The goal ``rooms`` grouped by the robots that reach them from their starts along moves of
    ``table`` that carry no penalty, the group with most rooms first; rooms no robot reaches so
    form a group with no robots, last."""
    reached = reached_by(table, PENALISED)
    order = {r: k for k, r in enumerate(table.robots)}
    groups: dict[tuple[str, ...], list[str]] = {}
    for room in rooms:
        whom = tuple(sorted(reached.get(room, ()), key=order.__getitem__))
        groups.setdefault(whom, []).append(room)
    return sorted(
        (Group(tuple(xs), whom) for whom, xs in groups.items()), key=lambda g: (not g.robots, -len(g.rooms), g.robots)
    )


def reached_by(table: CostTable, below: float = math.inf) -> dict[str, set[str]]:
    """Location -> the robots that reach it from their starts along moves of ``table`` that cost
    less than ``below`` (every move by default: where the robots' jobs or missing moves, not
    the chance constraint, keep them apart)."""
    steps: dict[tuple[str, str], list[str]] = {}
    for (robot, a, b), cost in table.single.items():
        if cost < below:
            steps.setdefault((robot, a), []).append(b)
    reached: dict[str, set[str]] = {}
    for robot in table.robots:
        start = table.start_location.get(robot, f"{robot}-start")
        seen, frontier = {start}, [start]
        while frontier:
            at = frontier.pop()
            for b in steps.get((robot, at), ()):
                if b not in seen:
                    seen.add(b)
                    frontier.append(b)
        for room in seen:
            reached.setdefault(room, set()).add(robot)
    return reached


def split_message(groups: list[Group], idle: dict[str, float], last: str, makespan: float, max_risk: float) -> str:
    """The warning's text: the groups, the group of ``last`` (the robot that ends the plan, at
    ``makespan`` s), and the robots of ``idle`` (robot -> its idle time, s) that cannot help it."""
    parts = [f"{_rooms(g.rooms)} ({' '.join(g.robots) or 'no robot'})" for g in groups]
    busiest = next(g for g in groups if last in g.robots)
    helpless = [r for r in idle if r not in busiest.robots]
    text = (
        f"within max_risk {max_risk:g}, the goal rooms fall into {len(groups)} groups that different robots "
        f"reach without a move over it: {'; '.join(parts)}. Work cannot pass between groups: {last} ends the "
        f"plan at {makespan:.1f} s in a group of {len(busiest.rooms)} rooms for {len(busiest.robots)} robots"
    )
    if helpless:
        idle_text = ", ".join(f"{r} {idle[r]:.0f} s" for r in helpless)
        text += f", while robots that cannot reach it stand idle ({idle_text})"
    return text + (
        f". A larger max_risk, or features the lidar can localise on near the doors into {last}'s group, would "
        "let more robots share its work."
    )


def _rooms(rooms: tuple[str, ...]) -> str:
    if len(rooms) <= NAMED:
        return ", ".join(rooms)
    return f"{len(rooms)} rooms ({', '.join(rooms[:NAMED])}, ...)"
