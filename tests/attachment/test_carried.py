"""Carried-belief costs on the team's clock: the planner's cost is the re-simulation's, runs are
remembered, and the paper's paired moves cost what the oracle said."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.plans import Plan

#: three robots on the corridor: r1 and r2 move together, r3 alone, then r1 and r3 together
PLAN: Plan = (
    (("r1", "r1-start", "L2"), ("r2", "r2-start", "L9")),
    (("r3", "r3-start", "L4"),),
    (("r1", "L2", "L3"), ("r3", "L4", "L8")),
    (("r1", "L3", "L7"),),
    (("r2", "L9", "L10"),),
)


@pytest.fixture(scope="module")
def three() -> CarriedCosts:
    _, _, carried = carried_problem("corridor-3robots.yaml", ("L3", "L4", "L6", "L7", "L8", "L2"), 3)
    return carried


def test_a_plan_costed_again_runs_nothing(three: CarriedCosts) -> None:
    first = three.plan_cost(PLAN)
    before = three.plans_run
    assert three.plan_cost(PLAN) == first and three.plans_run == before


def test_the_replay_is_the_planners_cost(three: CarriedCosts) -> None:
    """The re-simulation replays the plan (tmpnav.resimulate): the same costs, every robot at
    every control step of the clock, and the same schedule."""
    cost = three.plan_cost(PLAN)
    replayed = three.replay(PLAN)
    assert replayed.step_costs(len(PLAN), three.scenario.cost) == list(cost.steps)
    assert replayed.schedule == cost.schedule
    assert replayed.trajectories is not None
    steps = round(replayed.makespan / three.scenario.models.dt) + 1
    assert {r: len(t) for r, t in replayed.trajectories.items()} == dict.fromkeys(("r1", "r2", "r3"), steps)


def test_the_papers_paired_moves_cost_what_the_oracle_said() -> None:
    """A plan of paired moves only (the paper's: two robots, every action moves both) runs on the
    clock exactly as the oracle simulated each move, so the paper's numbers stay."""
    _, _, carried = carried_problem("corridor-2robots.yaml", ("L2", "L9", "L5", "L8"), 2)
    plan: Plan = ((("r1", "r1-start", "L2"), ("r2", "r2-start", "L9")), (("r1", "L2", "L5"), ("r2", "L9", "L8")))
    run = carried.replay(plan)
    first = carried.oracle.evaluate([carried.clock.request(carried.clock.initial(), plan[0])])[0]
    assert first is not None
    assert run.step_costs(2, carried.scenario.cost)[0] == pytest.approx(first.cost, rel=1e-12)
    r1, r2 = run.schedule.timeline("r1"), run.schedule.timeline("r2")
    assert r1[1].start == r2[1].start == max(r1[0].end, r2[0].end)  # the second pair waits for both


def test_robots_that_move_at_once_see_each_other_without_a_paired_move() -> None:
    """The paper's swap as two single moves: both start at 0, and when they pass each other the
    mutual observations couple their beliefs (cross-covariance), as in the paired move."""
    _, _, carried = carried_problem("corridor.yaml", ("L10", "L1"), 2)
    plan: Plan = ((("r1", "L1", "L10"),), (("r2", "L10", "L1"),))
    run = carried.replay(plan)
    assert [m.start for m in run.schedule.moves] == [0.0, 0.0]
    assert np.any(run.end.team.cov[0:3, 3:6] != 0.0)


def test_a_standing_robot_never_grows_less_certain() -> None:
    """A robot with nothing to do stands: no control, no motion noise, so its uncertainty never
    grows while the others drive (it may shrink: it still observes)."""
    _, _, carried = carried_problem("corridor-2robots.yaml", ("L2", "L5"), 2)
    plan: Plan = ((("r1", "r1-start", "L2"),), (("r1", "L2", "L5"),))
    run = carried.replay(plan)
    assert run.trajectories is not None
    traces = [np.trace(np.array(s.cov)) for s in run.trajectories["r2"]]
    assert len(traces) > 100 and all(b <= a + 1e-12 for a, b in itertools.pairwise(traces))


@pytest.mark.parametrize(
    ("config", "rooms", "head"),
    [
        ("corridor-3robots.yaml", ("L3", "L4", "L6", "L7"), ((("r1", "r1-start", "L3"),),)),
        ("building-20.yaml", ("S1", "S2", "N1", "N2"), ((("r1", "r1-start", "S1"),),)),
        # r1 starts in room A and comes back to it: it stands on one of A's instantiations
        ("two-rooms.yaml", ("A", "C", "B"), ((("r1", "A", "C"),), (("r1", "C", "A"),))),
    ],
)
def test_pairs_below_their_floors_are_not_asked_for(
    config: str, rooms: tuple[str, ...], head: Plan, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A sub-problem's pairs whose motion floors cannot save pair_min_gain are not asked of the
    oracle, and its table is the one with every pair asked for. The building's robots turn, then
    drive: under RPP the floors are the straight line's and cut few pairs."""
    _, _, carried = carried_problem(config, rooms, 2, "turn-then-drive", beams=True)
    goals = carried.scenario.goals
    skipped = [0]
    hopeless = CarriedCosts._hopeless

    def counted(self: CarriedCosts, *args: object) -> bool:
        out = hopeless(self, *args)  # type: ignore[arg-type]
        skipped[0] += out
        return out

    monkeypatch.setattr(CarriedCosts, "_hopeless", counted)
    fast = carried.subtable(head, ("r1", "r2"), rooms[1:], goals)
    monkeypatch.setattr(CarriedCosts, "_hopeless", lambda *args: False)
    every = carried.subtable(head, ("r1", "r2"), rooms[1:], goals)
    assert fast.pair == every.pair and fast.pair_duration == every.pair_duration and fast.single == every.single
    if config.startswith("building"):  # with a range sensor the floors are most of a move's cost
        assert skipped[0] > 0


def test_robots_whose_beliefs_ignore_each_other_are_never_paired(monkeypatch: pytest.MonkeyPatch) -> None:
    """With nav2's AMCL fusing its lidar alone, a paired move costs exactly its two single moves:
    a sub-problem asks the oracle for no pair, and its table is the one with every pair the entry
    rules allow asked for (none of which saves anything)."""
    _, _, carried = carried_problem("building-20.yaml", ("S1", "S2", "N1", "N2"), 2)
    goals, head = carried.scenario.goals, ((("r1", "r1-start", "S1"),),)
    stats = carried.oracle.stats
    before = stats.requests
    fast = carried.subtable(head, ("r1", "r2"), ("S2", "N1", "N2"), goals)
    singles = stats.requests - before
    monkeypatch.setattr(
        "tmpnav.attachment.carried.paired_moves", lambda _, g, at: ENCODINGS["mixed"].pair_filter(g, at)
    )
    before = stats.requests
    every = carried.subtable(head, ("r1", "r2"), ("S2", "N1", "N2"), goals)
    assert stats.requests - before > singles  # the pairs asked for
    assert fast.pair == every.pair == {} and fast.single == every.single
    assert stats.sims.joint_sims == 0  # they never see each other in their beliefs: factorised
