"""A plan's schedule when each move takes a known time: every robot at once, on one clock.

A task plan orders its steps, but the team does not take turns. Each robot makes its own
moves in the plan's order, one after the other; a move starts as soon as its robot has
ended its previous one, a paired move as soon as both of its robots have (the earlier one
waits), and a move may be held back by a delay. The plan's order between the steps of
different robots does not matter. This is the schedule of a cost table's durations
(context-free: a move takes the same time wherever it is made); with carried beliefs the
same rule runs on the team's clock (:mod:`tmpnav.attachment.clock`), where a move's time is
known only when it starts.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from tmpnav.results import Schedule, TimedMove
from tmpnav.types import CostTable, Goals, MoveKey

#: the time each move of a step takes (seconds, in the step's order), None if it cannot be made
Durations = Callable[[Sequence[MoveKey]], tuple[float, ...] | None]


def schedule(
    plan: Sequence[Sequence[MoveKey]],
    robots: Sequence[str],
    durations: Durations,
    delays: Mapping[int, float] | None = None,
    goals: Goals | None = None,
) -> Schedule | None:
    """The earliest schedule of ``plan`` (see the module docstring); ``delays`` hold plan steps
    back by that many seconds. None when a move has no duration (it cannot be made).

    With ``goals``, a move's duration (which ends after its target's service, as
    :meth:`CostTable.with_service` counts it) is split into the drive and the service, and a
    robot that arrives before its target's window opens waits there (``TimedMove.opens``);
    :meth:`Schedule.late` names the moves that arrive after it closes; a robot ``goals.held``
    holds starts free after its hold."""
    free = {r: goals.held_for(r) if goals is not None else 0.0 for r in robots}
    moves = []
    for k, step in enumerate(plan):
        times = durations(step)
        if times is None:
            return None
        start = max(free[m[0]] for m in step) + (delays or {}).get(k, 0.0)
        for (robot, origin, target), d in zip(step, times, strict=True):
            partner = next((m[0] for m in step if m[0] != robot), None)
            service = goals.service(target) if goals is not None else 0.0
            arrive = start + d - service
            opens = goals.opens(target, arrive) if goals is not None else 0.0
            moves.append(TimedMove(k, robot, origin, target, partner, free[robot], start, arrive, service, opens))
            free[robot] = arrive + opens + service
    return Schedule(tuple(robots), tuple(moves))


def table_durations(table: CostTable) -> Durations:
    """The durations of a cost table's moves (a pair's from ``pair_duration``, in either order)."""

    def durations(step: Sequence[MoveKey]) -> tuple[float, ...] | None:
        if len(step) == 1:
            d = table.duration.get(step[0])
            return None if d is None else (d,)
        m1, m2 = step[0], step[1]
        if (m1, m2) in table.pair_duration:
            return table.pair_duration[(m1, m2)]
        if (m2, m1) in table.pair_duration:
            d1, d2 = table.pair_duration[(m2, m1)]
            return d2, d1
        return None

    return durations
