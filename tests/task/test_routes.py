"""Edits between routes (tmpnav.task.routes): relocate, exchange and 2-opt* on a line of rooms,
screened on the single moves' table, never moving a robot's own target or its end."""

from __future__ import annotations

import itertools

from tmpnav.task.plans import Rules, with_origins
from tmpnav.task.routes import route_edits
from tmpnav.types import CostTable, Goals, Job

#: rooms on a line, 10 m apart; r1 starts at 0 m, r2 at 50 m
ROOMS = ("L1", "L2", "L3", "L4", "L5")
AT = {"r1-start": 0.0, "r2-start": 50.0, **{x: 10.0 * (k + 1) for k, x in enumerate(ROOMS)}}


def line_table() -> CostTable:
    """Cost and duration of a move: its length (m, at 1 m/s)."""
    single, duration = {}, {}
    for r in ("r1", "r2"):
        for a, b in itertools.product((f"{r}-start", *ROOMS), ROOMS):
            if a != b:
                single[(r, a, b)] = duration[(r, a, b)] = abs(AT[a] - AT[b])
    start = {"r1": "r1-start", "r2": "r2-start"}
    return CostTable(("r1", "r2"), ROOMS, (*start.values(), *ROOMS), start, single, {}, duration)


def plan_of(*steps: tuple[str, str]) -> tuple:
    return with_origins([(s,) for s in steps], {"r1": "r1-start", "r2": "r2-start"})


def routes(steps: list) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {"r1": [], "r2": []}
    for step in steps:
        for r, x in step:
            out[r].append(x)
    return out


def test_the_robot_that_finishes_last_gives_a_room_to_the_other() -> None:
    """r1 does all five rooms (50 m, 50 s); with time priced, moving L5 to r2 (10 m from it) is
    the best edit by the screen: the makespan falls to 40 s."""
    table, goals = line_table(), Goals(ROOMS, ())
    plan = plan_of(*[("r1", x) for x in ROOMS])
    rules = Rules(table.start_location, goals)
    edits = route_edits(plan, table, goals, rules, span_weight=1.0)
    assert edits, "an edit is better"
    best = routes(edits[0])
    assert best["r2"] and best["r1"] == [x for x in ROOMS if x not in best["r2"]]
    for edit in edits:
        assert rules.valid(with_origins(edit, table.start_location))


def test_crossed_routes_are_untangled_by_exchange_or_tails() -> None:
    """r1 goes to L5 and r2 to L1: both cross the line. An exchange (or the tails swapped) gives
    each the room next to it; on cost alone the plan is dearer, so the screen finds it."""
    table, goals = line_table(), Goals(("L1", "L5"), ())
    plan = plan_of(("r1", "L5"), ("r2", "L1"))
    edits = route_edits(plan, table, goals, Rules(table.start_location, goals), span_weight=0.0)
    assert routes(edits[0]) == {"r1": ["L1"], "r2": ["L5"]}


def test_no_plan_is_offered_when_the_routes_are_the_best_already() -> None:
    table, goals = line_table(), Goals(("L1", "L5"), ())
    plan = plan_of(("r1", "L1"), ("r2", "L5"))
    assert route_edits(plan, table, goals, Rules(table.start_location, goals), span_weight=1.0) == []


def test_a_robots_own_target_its_end_and_a_job_for_others_stay_where_they_are() -> None:
    """L5 is r1's own target, L4 is r1's end, L3's job is for r1 only: whatever the screen says,
    no edit moves them to r2."""
    table = line_table()
    goals = Goals(("L1", "L2", "L3"), (("r1", ("L5",)),), (Job("L3", robots=("r1",)),), (("r1", "L4"),))
    plan = plan_of(("r1", "L1"), ("r1", "L2"), ("r1", "L3"), ("r1", "L5"), ("r1", "L4"))
    rules = Rules(table.start_location, goals)
    assert rules.valid(plan)
    for edit in route_edits(plan, table, goals, rules, span_weight=1.0, limit=50):
        assert not {"L3", "L4", "L5"} & set(routes(edit)["r2"])


def test_routes_that_cross_the_line_are_swapped_and_turned_round() -> None:
    """r1 (at 0 m) drives to L4 then L5, r2 (at 50 m) to L2 then L1: 90 m in all. Swapping the
    tails alone gives 50 m (r1 L2, L1; r2 L4, L5); swapped and each turned round, 30 m: the
    screen finds that one first."""
    table, goals = line_table(), Goals(("L1", "L2", "L4", "L5"), ())
    plan = plan_of(("r1", "L4"), ("r1", "L5"), ("r2", "L2"), ("r2", "L1"))
    rules = Rules(table.start_location, goals)
    edits = route_edits(plan, table, goals, rules, span_weight=0.0)
    assert routes(edits[0]) == {"r1": ["L1", "L2"], "r2": ["L5", "L4"]}
    assert len({tuple(e) for e in edits}) == len(edits)  # no edit offered twice


def test_a_reordered_route_keeps_its_robots_end_last() -> None:
    """r2 must end at L1 (its dock): however its rooms are reordered, L1 stays its last."""
    table = line_table()
    goals = Goals(("L2", "L4", "L5"), (), (), (("r2", "L1"),))
    plan = plan_of(("r1", "L4"), ("r1", "L5"), ("r2", "L2"), ("r2", "L1"))
    rules = Rules(table.start_location, goals)
    assert rules.valid(plan)
    edits = route_edits(plan, table, goals, rules, span_weight=0.0, limit=50)
    assert edits
    for edit in edits:
        assert routes(edit)["r2"][-1] == "L1"


def test_a_room_the_table_does_not_know_is_screened_not_reordered() -> None:
    """A plan's room with no move in the table (an incumbent's, say) prices its route at inf:
    the screen offers nothing for it and nothing fails."""
    full = line_table()
    single = {m: c for m, c in full.single.items() if "L5" not in m[1:]}
    duration = {m: c for m, c in full.duration.items() if "L5" not in m[1:]}
    table = CostTable(full.robots, ROOMS[:4], full.locations[:-1], full.start_location, single, {}, duration)
    goals = Goals(ROOMS, ())
    plan = plan_of(("r1", "L5"), ("r1", "L1"), ("r2", "L4"), ("r2", "L2"), ("r2", "L3"))
    for edit in route_edits(plan, table, goals, Rules(table.start_location, goals), span_weight=0.0, limit=50):
        assert "L5" in routes(edit)["r1"] + routes(edit)["r2"]


def test_the_compiled_screen_adds_up_routes_as_the_plain_one() -> None:
    """Every route's (cost, time) from the vectorised sums equals _Screen.route's, for routes
    empty, whole, and through a move the table lacks (inf)."""
    from tmpnav.task.route_orders import Orders
    from tmpnav.task.routes import _Screen

    full = line_table()
    single = {m: c for m, c in full.single.items() if m != ("r2", "L1", "L3")}
    table = CostTable(full.robots, ROOMS, full.locations, full.start_location, single, {}, full.duration)
    goals = Goals(ROOMS, (), (Job("L2", service=3.0),))
    plain = _Screen(table, goals, 0.5)
    changes = [
        {"r1": ["L1", "L2"], "r2": []},
        {"r2": ["L1", "L3", "L5"]},
        {"r1": list(ROOMS), "r2": ["L4"]},
        {"r1": [], "r2": []},
    ]
    screened = Orders(table, goals, 0.5, ["r1", "r2"], list(ROOMS)).screen(changes)
    for changed, (as_is, order, reordered) in zip(changes, screened, strict=True):
        assert as_is == {r: plain.route(r, xs) for r, xs in changed.items()}
        assert reordered == {r: plain.route(r, xs) for r, xs in order.items()}
        assert {r: sorted(xs) for r, xs in order.items()} == {r: sorted(xs) for r, xs in changed.items()}


def test_every_edit_offered_is_better_as_its_steps_read() -> None:
    """The routes read from an edit's steps are the routes it was screened as, so each is better
    than the plan by the screen, robots' steps interleaved in the plan (r1's L4 is step 1, r2's L2
    step 2: after a 2-opt*, r2's head comes after its new tail's steps)."""
    from tmpnav.task.routes import _Screen

    table, goals = line_table(), Goals(("L1", "L2", "L4", "L5"), ())
    plan = plan_of(("r1", "L4"), ("r2", "L2"), ("r1", "L5"), ("r2", "L1"))
    rules = Rules(table.start_location, goals)
    screen = _Screen(table, goals, 1.0)
    value = lambda rooms: screen.value(screen.route(r, xs) for r, xs in rooms.items())  # noqa: E731
    now = value(routes([tuple((r, x) for r, _, x in step) for step in plan]))
    edits = route_edits(plan, table, goals, rules, span_weight=1.0, limit=50)
    assert edits
    for edit in edits:
        assert value(routes(edit)) < now


def three_homes_table() -> tuple[CostTable, dict[str, tuple[str, ...]]]:
    """Three robots, each with a home of two rooms: a move into its own home costs 1, into the
    next robot's home (r1 -> r2's, r2 -> r3's, r3 -> r1's) 10, into the third home 100."""
    homes = {"r1": ("X1", "X2"), "r2": ("Y1", "Y2"), "r3": ("Z1", "Z2")}
    robots = tuple(homes)
    rooms = tuple(x for xs in homes.values() for x in xs)
    start = {r: f"{r}-start" for r in robots}
    single, duration = {}, {}
    for k, r in enumerate(robots):
        price = {robots[k]: 1.0, robots[(k + 1) % 3]: 10.0, robots[(k + 2) % 3]: 100.0}
        for a, b in itertools.product((start[r], *rooms), rooms):
            if a != b:
                single[(r, a, b)] = next(p for owner, p in price.items() if b in homes[owner])
                duration[(r, a, b)] = 1.0
    return CostTable(robots, rooms, (*start.values(), *rooms), start, single, {}, duration), homes


def test_three_robots_pass_their_tails_round_where_no_two_can_swap() -> None:
    """Each robot does the next robot's home (60 in all). Every edit between two robots makes it
    dearer or saves little (a room relocated home saves 9; two robots' tails swapped put one
    robot in the third home, at 100 a room); the three tails passed round bring every robot home
    (6): the screen offers that edit first."""
    table, homes = three_homes_table()
    goals = Goals(table.rooms, ())
    plan = with_origins(
        [((r, x),) for r, owner in (("r1", "r2"), ("r2", "r3"), ("r3", "r1")) for x in homes[owner]],
        table.start_location,
    )
    rules = Rules(table.start_location, goals)
    edits = route_edits(plan, table, goals, rules, span_weight=0.0)
    assert {r: sorted(xs) for r, xs in _routes_of(edits[0]).items()} == {r: list(xs) for r, xs in homes.items()}


def _routes_of(steps: list) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for step in steps:
        for r, x in step:
            out.setdefault(r, []).append(x)
    return out


def test_robots_kept_apart_are_freed_of_the_price_by_an_edit_of_their_routes() -> None:
    """r1 does L1-L3 and r2 L5, L4: the best routes by the screen, so no edit is offered. Kept
    apart, the plan pays 20 more (a wait of r2's for r1): an edit of r1's or r2's route may free
    it of that, so edits up to 20 dearer by the screen are offered, none of them the plan's own
    routes again; robots kept apart that no edit can change leave nothing to offer."""
    from tmpnav.task.routes import KeptApartPrice

    table, goals = line_table(), Goals(ROOMS, ())
    plan = plan_of(("r1", "L1"), ("r1", "L2"), ("r1", "L3"), ("r2", "L5"), ("r2", "L4"))
    rules = Rules(table.start_location, goals)
    assert route_edits(plan, table, goals, rules, span_weight=0.0) == []
    now = routes(plan_steps(plan))
    edits = route_edits(plan, table, goals, rules, span_weight=0.0, apart=KeptApartPrice(20.0, frozenset({"r2"})))
    assert edits
    for edit in edits:
        assert routes(edit)["r2"] != now["r2"]
    assert route_edits(plan, table, goals, rules, span_weight=0.0, apart=KeptApartPrice(20.0, frozenset({"r9"}))) == []


def test_two_robots_nothing_keeps_apart_trade_their_whole_routes_first() -> None:
    """r1 does L1-L3 and r2 L5, L4: the best routes by the screen. Where keeping them apart leaves
    them in each other's way (robots docked in a row, the one behind with the work past the one
    in front), the first edit offered is the trade of their whole routes, which the screen prices
    dearer than the plan and would not offer; robots whose conflicts are cleared trade nothing."""
    from tmpnav.task.routes import KeptApartPrice

    table, goals = line_table(), Goals(ROOMS, ())
    plan = plan_of(("r1", "L1"), ("r1", "L2"), ("r1", "L3"), ("r2", "L5"), ("r2", "L4"))
    rules = Rules(table.start_location, goals)
    stuck = KeptApartPrice(1e6, frozenset({"r1", "r2"}), frozenset({("r1", "r2")}))
    edits = route_edits(plan, table, goals, rules, span_weight=1.0, apart=stuck)
    assert routes(edits[0]) == {"r1": ["L5", "L4"], "r2": ["L1", "L2", "L3"]}
    assert rules.valid(with_origins(edits[0], table.start_location))
    cleared = KeptApartPrice(1e6, frozenset({"r1", "r2"}))
    assert all(
        routes(e) != {"r1": ["L5", "L4"], "r2": ["L1", "L2", "L3"]}
        for e in route_edits(plan, table, goals, rules, span_weight=1.0, apart=cleared)
    )


def test_a_robot_whose_own_target_stays_does_not_trade() -> None:
    """r1 must visit L1 itself (goals.per_robot): its route cannot go to r2, so no trade."""
    from tmpnav.task.routes import KeptApartPrice

    table, goals = line_table(), Goals(("L2", "L3", "L4", "L5"), (("r1", ("L1",)),))
    plan = plan_of(("r1", "L1"), ("r1", "L2"), ("r2", "L5"), ("r2", "L4"), ("r2", "L3"))
    rules = Rules(table.start_location, goals)
    stuck = KeptApartPrice(1e6, frozenset({"r1", "r2"}), frozenset({("r1", "r2")}))
    for edit in route_edits(plan, table, goals, rules, span_weight=1.0, apart=stuck):
        assert "L1" in routes(edit)["r1"]


def plan_steps(plan: tuple) -> list:
    return [tuple((r, x) for r, _, x in step) for step in plan]
