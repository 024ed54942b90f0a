"""A replan's incumbent with its new goals put in (tmpnav.task.plans.with_missing): each room
it leaves undone inserted where the single moves' costs rise least."""

from __future__ import annotations

from dataclasses import replace

from tests.task.test_routes import line_table, plan_of, routes
from tmpnav.task.plans import Rules, targets_only, with_missing, with_origins, without_revisits
from tmpnav.types import Goals

START = {"r1": "r1-start", "r2": "r2-start"}


def test_a_new_room_goes_where_it_costs_least() -> None:
    """On the line (r1 from 0 m, r2 from 50 m), L2 between r1's L1 and L3 costs nothing more."""
    table, goals = line_table(), Goals(("L1", "L2", "L3", "L5"), ())
    plan = plan_of(("r1", "L1"), ("r2", "L5"), ("r1", "L3"))
    done = with_missing(plan, Rules(START, goals), table)
    assert routes(targets_only(done)) == {"r1": ["L1", "L2", "L3"], "r2": ["L5"]}
    assert Rules(START, goals).valid(done)


def test_a_room_near_the_other_robot_goes_to_it() -> None:
    table, goals = line_table(), Goals(("L1", "L4", "L5"), ())
    done = with_missing(plan_of(("r1", "L1"), ("r2", "L5")), Rules(START, goals), table)
    assert routes(targets_only(done)) == {"r1": ["L1"], "r2": ["L5", "L4"]}  # 10 m more for r2, 30 for r1


def test_a_robots_own_target_goes_to_that_robot() -> None:
    table, goals = line_table(), Goals(("L1",), (("r2", ("L2",)),))
    done = with_missing(plan_of(("r1", "L1")), Rules(START, goals), table)
    assert routes(targets_only(done)) == {"r1": ["L1"], "r2": ["L2"]}


def test_a_complete_plan_or_an_unreachable_room_is_left_as_it_is() -> None:
    table, goals = line_table(), Goals(("L1", "L5"), ())
    plan = plan_of(("r1", "L1"), ("r2", "L5"))
    assert with_missing(plan, Rules(START, goals), table) == plan
    cut = replace(table, single={m: c for m, c in table.single.items() if m[2] != "L3"})
    missing = Goals(("L1", "L3", "L5"), ())
    assert with_missing(plan, Rules(START, missing), cut) == plan  # no move reaches L3: nothing to put in


def test_a_move_into_a_room_the_robot_stands_in_is_no_move() -> None:
    """A replan whose robot has driven into its next goal room starts it there: the room is
    visited, and the plan under way without that move is the search's seed (with it, the
    rules refused the seed and OR-Tools started from nothing)."""
    goals = Goals(("L1", "L2", "L3"), ())
    rules = Rules({"r1": "L1", "r2": "r2-start"}, goals)
    under_way = ((("r1", "L1"),), (("r1", "L2"),), (("r2", "L3"),))
    assert not rules.valid(with_origins(under_way, rules.start_location))
    kept = without_revisits(under_way, rules)
    assert kept == ((("r1", "L2"),), (("r2", "L3"),))
    assert rules.valid(with_origins(kept, rules.start_location))
    # a room another robot has visited by then is dropped too; from a step the rules refuse for
    # another reason (a robot not in the team), the steps as they are
    assert without_revisits(((("r1", "L2"),), (("r2", "L2"), ("r1", "L3"))), rules) == (
        (("r1", "L2"),),
        (("r1", "L3"),),
    )
    stranger = ((("r9", "L3"),), (("r1", "L2"),))
    assert without_revisits(stranger, rules) == stranger
