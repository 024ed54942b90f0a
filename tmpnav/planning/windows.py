"""Jobs' windows a plan cannot meet, found before the search and after it.

A job's window (``goals.jobs``: [earliest, latest] on the team's clock) bounds when a robot may
arrive at its room. Before the search, each window is checked against the earliest arrival
possible: the least time floor (:mod:`tmpnav.attachment.floors`: the least any move of the
roadmap takes, whatever the beliefs) of a move into the room from the start of a robot that may
do the job, after the robot's hold at its station (a replan's ``goals.held``). A robot that
must first go elsewhere arrives later still, so a window that closes before that floor is met
by no plan. After the search, a plan that still arrives late (every
plan the search tried was) gets the same error, with the arrival of its latest move.
"""

from __future__ import annotations

import math

from tmpnav.attachment.floors import motion_floors
from tmpnav.errors import WindowError
from tmpnav.oracle.executors import library
from tmpnav.planning.run import TaskRun
from tmpnav.results import Schedule


def check_windows(run: TaskRun) -> None:
    """Raise WindowError for the first window (in the goals' order) that closes before any
    robot that may do the job can get there."""
    goals = run.goals
    if not goals.windows:
        return
    canonical = run.canonical
    paths = library(canonical.oracle.ctx).graph
    floors = motion_floors(run.scenario, paths, canonical.start_location, goals, run.choice.costs == "carried")
    for room, (_, latest) in goals.windows.items():
        earliest = min(
            (
                goals.held_for(r) + d  # a robot held at its station leaves after its hold
                for (r, origin, x), d in floors.duration.items()
                if x == room and origin == canonical.start_location[r] and goals.may_visit(r, room)
            ),
            default=math.inf,
        )
        if earliest > latest:
            can = "never (no robot that may do the job reaches it)" if math.isinf(earliest) else f"{earliest:.1f} s"
            raise WindowError(
                f"{run.scenario.source.name}: goals.jobs.{room}.window: it closes at {latest:g} s, but the earliest "
                f"arrival possible is {can} (the quickest robot allowed, driving there first); expected a window "
                "that closes later",
                room,
                latest,
                earliest,
                certain=True,
            )


def check_arrivals(run: TaskRun, schedule: Schedule | None) -> None:
    """Raise WindowError if the plan found arrives after a window closes (no plan tried met it)."""
    late = schedule.late(run.goals.windows) if schedule is not None else ()
    if late:
        m = late[0]
        latest = run.goals.windows[m.target][1]
        raise WindowError(
            f"{run.scenario.source.name}: goals.jobs.{m.target}.window: it closes at {latest:g} s, and the best "
            f"plan found arrives at {m.end:.1f} s ({m.robot}); no plan found meets every window; expected a window "
            "that closes later, fewer goals before it, or another robot allowed to do it",
            m.target,
            latest,
            m.end,
        )
