"""Unloading (tmpnav.task.balance): relocations chained from the robot that finishes last, on a
small synthetic table of rooms on a line (no oracle)."""

from __future__ import annotations

import itertools

from tmpnav.task.balance import Moves, routes_of, unloadings
from tmpnav.task.plans import Rules, targets_only, with_origins
from tmpnav.task.routes import route_edits
from tmpnav.types import RISK_PENALTY, CostTable, Goals

#: eight rooms on a line, 10 m apart from 10 m on; four robots, at 0, 90, 35 and 55 m; a move
#: costs a tenth of its length
ROBOTS = ("r1", "r2", "r3", "r4")
ROOMS = tuple(f"L{k}" for k in range(1, 9))
AT = {
    "r1-start": 0.0,
    "r2-start": 90.0,
    "r3-start": 35.0,
    "r4-start": 55.0,
    **{x: 10.0 * (k + 1) for k, x in enumerate(ROOMS)},
}
START = {r: f"{r}-start" for r in ROBOTS}


def line_table() -> CostTable:
    """Every robot's moves: duration its length (m, at 1 m/s), cost a tenth of it."""
    single, duration = {}, {}
    for r in ROBOTS:
        for a, b in itertools.product((START[r], *ROOMS), ROOMS):
            if a != b:
                duration[(r, a, b)] = abs(AT[a] - AT[b])
                single[(r, a, b)] = 0.1 * duration[(r, a, b)]
    return CostTable(ROBOTS, ROOMS, (*START.values(), *ROOMS), START, single, {}, duration)


def unbalanced() -> list:
    """r1 takes L1-L4 and r2 L8-L5 (40 s each); r3 and r4, in the middle, stand idle."""
    order = [("r1", x) for x in ROOMS[:4]] + [("r2", x) for x in reversed(ROOMS[4:])]
    plan = with_origins([(move,) for move in order], START)
    return targets_only(plan)


def times(steps: list, legs: Moves) -> dict[str, float]:
    rooms = {r: [x for _, x in route] for r, route in routes_of(steps).items()}
    return {r: legs.route(r, rooms.get(r, []))[1] for r in ROBOTS}


def test_each_unloading_ends_the_fleet_sooner_and_gives_the_idle_robots_work() -> None:
    table, goals = line_table(), Goals(ROOMS, ())
    rules, legs = Rules(START, goals), Moves(table, goals)
    steps = unbalanced()
    chain = list(unloadings(steps, list(ROBOTS), lambda *_: True, legs, 1.0, depth=8))
    assert chain, "the idle robots can help"
    spans = [max(times(steps, legs).values())] + [max(times(s, legs).values()) for _, s in chain]
    assert all(b <= a for a, b in itertools.pairwise(spans)) and spans[-1] < spans[0]
    for changed, edited in chain:
        assert rules.valid(with_origins(edited, START))
        for r, rooms in changed.items():  # the changed routes are those of the steps
            assert rooms == [x for _, x in routes_of(edited).get(r, [])]
    last = times(chain[-1][1], legs)
    assert all(t > 0 for t in last.values()), "every robot has work at the end of the chain"


def test_a_room_the_other_robots_may_not_take_stays() -> None:
    table, goals = line_table(), Goals(ROOMS, ())
    chain = unloadings(unbalanced(), list(ROBOTS), lambda *_: False, Moves(table, goals), 1.0, depth=8)
    assert list(chain) == []


def test_route_edits_offer_an_unloading_where_the_makespan_counts() -> None:
    """The best edit by the screen ends the fleet sooner than any one relocation can: r1 and r2
    end together at 40 s, so a room taken from one leaves the other last."""
    table, goals = line_table(), Goals(ROOMS, ())
    rules, legs = Rules(START, goals), Moves(table, goals)
    plan = with_origins(unbalanced(), START)
    best = route_edits(plan, table, goals, rules, span_weight=1.0)[0]
    assert max(times(best, legs).values()) <= 40.0 - 10.0


def test_an_ejection_chain_passes_work_on_where_no_one_robot_can_take_it() -> None:
    """a (20 s) has rooms only b can enter, and b ends at 19 s: any room of a's makes b end at
    20 s or later. b takes X2 and hands Y2 on to c, which can enter only b's rooms: all three end
    before 20 s."""
    moves = {
        "a": {("a0", "X1"): 10, ("X1", "X2"): 10, ("a0", "X2"): 15, ("X2", "X1"): 10},
        "b": {("b0", "Y1"): 10, ("Y1", "Y2"): 9, ("b0", "Y2"): 12, ("Y2", "Y1"): 9, ("b0", "X1"): 14, ("b0", "X2"): 12},
        "c": {("c0", "Y1"): 6, ("c0", "Y2"): 5, ("Y1", "Y2"): 9, ("Y2", "Y1"): 9},
    }
    for a, b, t in (("Y1", "X2", 5), ("Y2", "X2", 5), ("Y1", "X1", 8), ("Y2", "X1", 8), ("X1", "X2", 10)):
        moves["b"].update({(a, b): t, (b, a): t})
    single = {(r, o, t): float(v) for r, table in moves.items() for (o, t), v in table.items()}
    start = {"a": "a0", "b": "b0", "c": "c0"}
    rooms = ("X1", "X2", "Y1", "Y2")
    table = CostTable(("a", "b", "c"), rooms, (*start.values(), *rooms), start, single, {}, dict(single))
    goals = Goals(rooms, ())
    plan = targets_only(with_origins([(("a", "X1"),), (("a", "X2"),), (("b", "Y1"),), (("b", "Y2"),)], start))
    moves_ = Moves(table, goals)
    (changed, steps), *_ = unloadings(plan, ["a", "b", "c"], lambda *_: True, moves_, 1.0, depth=1)
    assert changed == {"a": ["X1"], "b": ["Y1", "X2"], "c": ["Y2"]}
    assert Rules(start, goals).valid(with_origins(steps, start))


def test_work_passes_along_safe_robots_rather_than_over_the_chance_constraint() -> None:
    """As above, but c may also take X2 directly, over the chance constraint (its move into X2
    is penalised): the ejection chain, every move within it, is the unloading."""
    moves = {
        "a": {("a0", "X1"): 10, ("X1", "X2"): 10, ("a0", "X2"): 15, ("X2", "X1"): 10},
        "b": {("b0", "Y1"): 10, ("Y1", "Y2"): 9, ("b0", "Y2"): 12, ("Y2", "Y1"): 9, ("b0", "X1"): 14, ("b0", "X2"): 12},
        "c": {("c0", "Y1"): 6, ("c0", "Y2"): 5, ("Y1", "Y2"): 9, ("Y2", "Y1"): 9, ("c0", "X2"): 5},
    }
    for a, b, t in (("Y1", "X2", 5), ("Y2", "X2", 5), ("Y1", "X1", 8), ("Y2", "X1", 8), ("X1", "X2", 10)):
        moves["b"].update({(a, b): t, (b, a): t})
    duration = {(r, o, t): float(v) for r, table in moves.items() for (o, t), v in table.items()}
    single = {**duration, ("c", "c0", "X2"): 5.0 + RISK_PENALTY * 0.2}  # a collision bound 0.2 over
    start = {"a": "a0", "b": "b0", "c": "c0"}
    rooms = ("X1", "X2", "Y1", "Y2")
    table = CostTable(("a", "b", "c"), rooms, (*start.values(), *rooms), start, single, {}, duration)
    goals = Goals(rooms, ())
    plan = targets_only(with_origins([(("a", "X1"),), (("a", "X2"),), (("b", "Y1"),), (("b", "Y2"),)], start))
    (changed, steps), *_ = unloadings(plan, ["a", "b", "c"], lambda *_: True, Moves(table, goals), 1.0, depth=1)
    assert changed == {"a": ["X1"], "b": ["Y1", "X2"], "c": ["Y2"]}
    assert Rules(start, goals).valid(with_origins(steps, start))
