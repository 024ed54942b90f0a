"""Where the chance constraint splits a fleet (tmpnav.report.reach): the goal rooms grouped by the
robots that reach them without a move over it, on small synthetic tables (no oracle)."""

from __future__ import annotations

from tmpnav.report.reach import reach_groups, reached_by, split_message
from tmpnav.types import RISK_PENALTY, CostTable

#: a move over the chance constraint: its collision bound 0.1 over max_risk
OVER = 5.0 + RISK_PENALTY * 0.1


def table(moves: dict[tuple[str, str, str], float]) -> CostTable:
    robots = tuple(sorted({r for r, _, _ in moves}))
    start = {r: f"{r}-start" for r in robots}
    rooms = tuple(sorted({b for _, _, b in moves}))
    return CostTable(robots, rooms, (*start.values(), *rooms), start, dict(moves), {}, dict.fromkeys(moves, 10.0))


def test_rooms_reached_only_over_the_constraint_form_their_own_group() -> None:
    """a reaches A1 and, through it, A2; b reaches B1 only; both enter each other's rooms only over
    the constraint, and nobody reaches C within it."""
    moves = {
        ("a", "a-start", "A1"): 5.0,
        ("a", "A1", "A2"): 5.0,
        ("a", "a-start", "B1"): OVER,
        ("a", "A2", "C"): OVER,
        ("b", "b-start", "B1"): 5.0,
        ("b", "b-start", "A1"): OVER,
        ("b", "B1", "A2"): OVER,
    }
    groups = reach_groups(table(moves), ["A1", "A2", "B1", "C"])
    assert [(g.rooms, g.robots) for g in groups] == [(("A1", "A2"), ("a",)), (("B1",), ("b",)), (("C",), ())]


def test_a_fleet_that_reaches_every_room_is_one_group() -> None:
    moves = {(r, f"{r}-start", x): 5.0 for r in ("a", "b") for x in ("A1", "A2")}
    moves[("b", "b-start", "A2")] = OVER  # b reaches A2 through A1 all the same
    moves[("b", "A1", "A2")] = 5.0
    (group,) = reach_groups(table(moves), ["A1", "A2"])
    assert group.robots == ("a", "b")


def test_the_message_names_the_groups_the_busiest_and_the_robots_idle_outside_it() -> None:
    moves = {("a", "a-start", f"A{k}"): 5.0 for k in range(6)} | {
        ("b", "b-start", "B1"): 5.0,
        ("c", "c-start", "B1"): 5.0,
    }
    groups = reach_groups(table(moves), [*(f"A{k}" for k in range(6)), "B1"])
    text = split_message(groups, {"b": 290.0, "c": 300.0}, "a", 310.0, 0.05)
    assert text.startswith("within max_risk 0.05, the goal rooms fall into 2 groups")
    assert "6 rooms (A0, A1, A2, A3, ...) (a); B1 (b c)" in text
    assert "a ends the plan at 310.0 s in a group of 6 rooms for 1 robots" in text
    assert "stand idle (b 290 s, c 300 s)" in text


def test_every_move_counts_where_the_constraint_is_not_asked_about() -> None:
    """Over the constraint b reaches A1 too: that split is the constraint's. A2 only a has a
    move into, and C no robot: nothing but the table keeps the others out."""
    moves = {
        ("a", "a-start", "A1"): 5.0,
        ("a", "A1", "A2"): 5.0,
        ("b", "b-start", "B1"): 5.0,
        ("b", "b-start", "A1"): OVER,
    }
    anyway = reached_by(table(moves))
    assert anyway["A1"] == {"a", "b"} and anyway["A2"] == {"a"} and anyway["B1"] == {"b"}
    assert "C" not in anyway
