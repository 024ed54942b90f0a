"""The repair rule of a revision (tmpnav.task.plans.with_missing): a goal the rest of the old plan
leaves over goes where the single moves' costs rise least among the places where every robot
still arrives within its jobs' windows, and a robot held at its station (Goals.held) starts late."""

from __future__ import annotations

from tmpnav.task.plans import Rules, with_missing, with_origins
from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, Goals, Job

START = {"r1": "S1", "r2": "S2"}
#: (robot, from, to): (cost, seconds)
MOVES = {
    ("r1", "S1", "A"): (1.0, 10.0),
    ("r1", "A", "X"): (1.0, 10.0),  # the cheapest place for X, but r1 gets there at 20 s
    ("r1", "S1", "X"): (8.0, 20.0),
    ("r1", "X", "A"): (8.0, 10.0),
    ("r2", "S2", "B"): (1.0, 5.0),
    ("r2", "S2", "X"): (5.0, 5.0),  # dearer, on time
    ("r2", "X", "B"): (1.0, 5.0),
    ("r2", "B", "X"): (9.0, 30.0),
}
TABLE = CostTable(
    ("r1", "r2"),
    ("A", "B", "X"),
    ("S1", "S2", "A", "B", "X"),
    START,
    {m: c for m, (c, _) in MOVES.items()},
    {},
    {m: d for m, (_, d) in MOVES.items()},
)
REST = with_origins([(("r1", "A"),), (("r2", "B"),)], START)  # the old plan's rest, without X


def test_a_goal_left_over_goes_where_its_window_is_met() -> None:
    goals = Goals(("A", "B", "X"), (), (Job("X", window=(0.0, 15.0)),))
    plan = with_missing(REST, Rules(START, goals), TABLE)
    assert [m for step in plan for m in step if m[2] == "X"] == [("r2", "S2", "X")]
    timed = schedule(plan, TABLE.robots, table_durations(TABLE), goals=goals)
    assert timed is not None and not timed.late(goals.windows)


def test_without_a_window_the_cheapest_place_is_taken() -> None:
    goals = Goals(("A", "B", "X"), ())
    plan = with_missing(REST, Rules(START, goals), TABLE)
    assert [m for step in plan for m in step if m[2] == "X"] == [("r1", "A", "X")]


def test_a_robot_held_at_its_station_starts_after_its_hold() -> None:
    goals = Goals(("A", "B"), (), held=(("r2", 12.5),))
    timed = schedule(REST, TABLE.robots, table_durations(TABLE), goals=goals)
    assert timed is not None
    assert [(m.robot, m.ready, m.start, m.end) for m in timed.moves] == [
        ("r1", 0.0, 0.0, 10.0),
        ("r2", 12.5, 12.5, 17.5),
    ]
