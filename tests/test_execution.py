"""Plan execution (``tmpnav simulate``): the waypoint switching, the team executing its schedule
at once (a robot waits for its partner, and for a move's planned start), the makespan reported,
the wall hits and robot contacts counted, and the paper's result on the corridor."""

from __future__ import annotations

import csv
import dataclasses
import io
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pytest

from tmpnav.errors import TmpnavError
from tmpnav.execution import (
    ARRIVED,
    Draws,
    QueuedMove,
    Rate,
    Session,
    SessionTrace,
    error_summary,
    errors_csv,
    execute,
    hits_csv,
    moves_csv,
    reached,
    sessions_csv,
)
from tmpnav.pipeline import PlanOptions, load_world, plan
from tmpnav.report.text import plan_summary
from tmpnav.results import PlanReport, Schedule, TimedMove
from tmpnav.types import Goals, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility

ROOT = Path(__file__).resolve().parents[1]
CORRIDOR = ROOT / "configs" / "corridor.yaml"
START = np.array([0.0, 0.0])
World3 = tuple[Scenario, World, LandmarkVisibility]  # the corridor: scenario, world, landmark visibility
WAYPOINT = np.array([2.0, 0.0])


def est(x: float, y: float) -> np.ndarray:
    return np.array([x, y, 0.0])


def test_a_waypoint_is_reached_when_the_estimate_is_close() -> None:
    assert reached(est(2.0 - 0.9 * ARRIVED, 0.0), START, WAYPOINT)
    assert reached(est(2.0, 0.9 * ARRIVED), START, WAYPOINT)


def test_a_waypoint_is_reached_when_the_robot_is_abreast_of_it_or_past_it() -> None:
    # 30 cm to the side: turning on the spot towards it would only add heading noise
    assert reached(est(2.0, 0.3), START, WAYPOINT)
    assert reached(est(2.2, -0.3), START, WAYPOINT)


def test_a_waypoint_ahead_is_not_reached() -> None:
    assert not reached(est(1.8, 0.0), START, WAYPOINT)
    assert not reached(est(1.0, 0.5), START, WAYPOINT)
    assert not reached(est(-0.5, 0.0), START, WAYPOINT)


# ---------------------------------------------------------------- the team on one clock, by hand


def move(
    step: int, robot: str, points: Sequence[tuple[float, float]], partner: str | None = None, start: int = 0
) -> QueuedMove:
    """A queued move along ``points`` (corridor coordinates), planned to start at step ``start``."""
    return QueuedMove(
        step=step,
        robot=robot,
        origin="here",
        target="there",
        partner=partner,
        nodes=tuple(range(len(points))),
        points=np.array(points, dtype=float),
        start=start,
        steps=40,
        arrivals=(None,) * (len(points) - 1),
    )


@pytest.fixture(scope="module")
def corridor_world() -> World3:
    scenario, world = load_world(CORRIDOR)
    return scenario, world, LandmarkVisibility(world, scenario.models.landmark_sensor.range)


def run(
    corridor_world: World3,
    queues: Mapping[str, tuple[QueuedMove, ...]],
    mutual: bool = True,
    seed: int = 0,
    alphas: tuple[float, float, float, float] | None = None,
) -> SessionTrace:
    """A session on the corridor (r1 in L1, r2 in L10), with other motion noise if given."""
    scenario, world, vis = corridor_world
    if alphas is not None:
        scenario = dataclasses.replace(scenario, models=dataclasses.replace(scenario.models, motion_noise=alphas))
    draws = Draws.draw(seed, 0, 2, 2000, world.landmark_xy.shape[0])
    return Session(scenario, world, queues, draws, vis, mutual).run()


def session(
    corridor_world: World3, queues: Mapping[str, tuple[QueuedMove, ...]], mutual: bool = True
) -> dict[tuple[int, str], TimedMove]:
    """(plan step, robot) -> the move as executed, in a session on the corridor (r1 in L1, r2 in L10)."""
    trace = run(corridor_world, queues, mutual)
    assert not trace.truncated
    return {(m.step, m.robot): m for m in trace.moves}


#: r1 drives out of L1 to the corridor alone, then r1 and r2 (from L10) move together
R1_OUT = [(5.0, 12.5), (5.0, 11.0), (5.0, 9.5)]
R1_EAST = [(5.0, 9.5), (8.0, 9.5)]
R2_OUT = [(5.0, 6.5), (5.0, 8.0)]


def test_a_robot_waits_for_its_partner_and_the_partner_does_not_wait(corridor_world: World3) -> None:
    ran = session(
        corridor_world,
        {
            "r1": (move(0, "r1", R1_OUT), move(1, "r1", R1_EAST, partner="r2")),
            "r2": (move(1, "r2", R2_OUT, partner="r1"),),
        },
    )
    first, r1, r2 = ran[(0, "r1")], ran[(1, "r1")], ran[(1, "r2")]
    assert first.start == 0.0 and first.end > 0.0
    assert r1.start == r2.start == first.end  # the paired move starts when r1 is there
    assert (r1.ready, r1.wait) == (first.end, 0.0)
    assert (r2.ready, r2.wait) == (0.0, first.end)  # r2 stood in L10 meanwhile
    schedule = Schedule(("r1", "r2"), (first, r1, r2))
    assert schedule.makespan == max(r1.end, r2.end) and schedule.waits("r2") == first.end


def test_no_move_starts_before_its_planned_start(corridor_world: World3) -> None:
    later = 60  # control steps: later than r1 can be in the corridor
    ran = session(
        corridor_world,
        {
            "r1": (move(0, "r1", R1_OUT), move(1, "r1", R1_EAST, partner="r2", start=later)),
            "r2": (move(1, "r2", R2_OUT, partner="r1", start=later),),
        },
    )
    dt = corridor_world[0].models.dt
    assert ran[(0, "r1")].end < later * dt
    assert ran[(1, "r1")].start == ran[(1, "r2")].start == later * dt
    assert ran[(1, "r1")].wait == later * dt - ran[(0, "r1")].end


def test_a_held_back_move_departs_at_its_planned_start_not_when_its_robot_is_ready(
    corridor_world: World3,
) -> None:
    """r1's second move (alone) is held back, as a planner keeping it clear of another robot
    would: r1 stands where its first move ended until the planned start, then departs at once."""
    later = 70
    ran = session(corridor_world, {"r1": (move(0, "r1", R1_OUT), move(1, "r1", R1_EAST, start=later))})
    dt = corridor_world[0].models.dt
    first, second = ran[(0, "r1")], ran[(1, "r1")]
    assert first.end < later * dt
    assert (second.ready, second.start) == (first.end, later * dt)
    assert second.wait == later * dt - first.end and second.end > second.start
    # not held back: it departs the moment r1 is ready
    ran = session(corridor_world, {"r1": (move(0, "r1", R1_OUT), move(1, "r1", R1_EAST))})
    assert ran[(1, "r1")].start == ran[(0, "r1")].end


def test_robots_make_their_own_moves_at_once(corridor_world: World3) -> None:
    ran = session(
        corridor_world,
        {"r1": (move(0, "r1", R1_OUT),), "r2": (move(1, "r2", R2_OUT),)},
        mutual=False,
    )
    assert ran[(0, "r1")].start == ran[(1, "r2")].start == 0.0  # step 1 does not wait for step 0


def test_a_schedule_whose_robots_wait_for_each_other_is_refused(corridor_world: World3) -> None:
    """r1 would pair with r2 in step 1 first, r2 with r1 in step 2 first: neither can start."""
    queues = {
        "r1": (move(1, "r1", R1_OUT, partner="r2"), move(2, "r1", R1_EAST, partner="r2")),
        "r2": (move(2, "r2", R2_OUT, partner="r1"), move(1, "r2", R2_OUT[::-1], partner="r1")),
    }
    with pytest.raises(TmpnavError, match="cannot be executed: r1 at step 2 waits for r2, r2 at step 3 waits for r1"):
        session(corridor_world, queues)


# ---------------------------------------------------------------- wall hits and robot contacts

#: r1 out of L1 and west along the corridor 0.4 m from its north wall (clearance 0.35 m against
#: a radius of 0.25 m: 5 cm of margin), and the same drive along the corridor's middle
ALONG_THE_WALL = [(5.0, 9.5), (4.0, 10.6), (0.8, 10.6)]
ALONG_THE_MIDDLE = [(5.0, 9.5), (1.0, 9.5)]
LARGE_NOISE = (0.3, 0.0, 0.3, 0.05)  # the corridor's: (0.01, 0, 0.02, 0.01)


def test_a_robot_driving_along_a_wall_with_large_noise_hits_it(corridor_world: World3) -> None:
    """The west corridor has no landmark in range, so r1 drives on dead reckoning: in 6 of 8
    sessions its true pose hits the wall (in the others its start error lies away from it)."""
    queues = {"r1": (move(0, "r1", R1_OUT), move(1, "r1", ALONG_THE_WALL))}
    traces = [run(corridor_world, queues, seed=seed, alphas=LARGE_NOISE) for seed in range(8)]
    assert sum(t.wall_hits["r1"] > 0 for t in traces) >= 6
    for t in traces:
        assert not t.truncated and t.wall_hits["r2"] == 0  # r2 stands in L10
        assert t.contacts == {"r1": 0, "r2": 0}


@pytest.mark.parametrize("seed", range(4))
def test_robots_far_from_walls_and_each_other_hit_nothing(corridor_world: World3, seed: int) -> None:
    queues = {"r1": (move(0, "r1", R1_OUT), move(1, "r1", ALONG_THE_MIDDLE)), "r2": (move(2, "r2", R2_OUT),)}
    trace = run(corridor_world, queues, seed=seed)
    assert not trace.truncated
    assert trace.wall_hits == {"r1": 0, "r2": 0} and trace.contacts == {"r1": 0, "r2": 0}


def test_each_wall_hit_is_placed_where_it_began_and_lasts_its_steps(corridor_world: World3) -> None:
    """Every contact is one HitEvent at its first step: the robot, the move under way, a true
    position within the robot's radius of the wall, and as many steps as the counts have; a
    contact that goes on is not recorded again."""
    queues = {"r1": (move(0, "r1", R1_OUT), move(1, "r1", ALONG_THE_WALL))}
    scenario, world, _ = corridor_world
    radius = scenario.robots[0].radius
    hits = 0
    for seed in range(8):
        t = run(corridor_world, queues, seed=seed, alphas=LARGE_NOISE)
        walls = [e for e in t.hit_events if e.kind == "wall"]
        assert sum(e.steps for e in walls) == t.wall_hits["r1"] and all(e.robot == "r1" for e in walls)
        for e in walls:
            i, j, inside = world.grid.cells(np.array([[e.x, e.y]]))
            assert inside[0] and world.clearance[i[0], j[0]] <= radius  # the definition counted
            assert e.step in (0, 1) and e.t > 0 and e.error >= 0 and e.own_std > 0
        hits += len(walls)
    assert hits >= 6


def test_robots_that_come_closer_than_their_radii_touch(corridor_world: World3) -> None:
    """r2 drives up to 0.4 m from r1, which stands in L1: radii 0.25 m each."""
    r2_up = [(5.0, 6.5), (5.0, 8.0), (5.0, 9.5), (5.0, 11.0), (5.0, 12.1)]
    trace = run(corridor_world, {"r2": (move(0, "r2", r2_up),)})
    assert trace.contacts["r1"] == trace.contacts["r2"] > 0  # every step r2 stands there
    assert trace.wall_hits == {"r1": 0, "r2": 0}
    touches = [e for e in trace.hit_events if e.kind == "robot"]
    assert {e.robot for e in touches} == {"r1", "r2"} and all(e.steps == trace.contacts[e.robot] for e in touches)


def test_a_rate_of_executions_has_its_clopper_pearson_interval() -> None:
    assert Rate(0, 25).text() == "0/25 = 0.0% (95% CI 0.0-13.7%)"
    assert Rate(5, 100).interval == (pytest.approx(0.0164, abs=1e-4), pytest.approx(0.1128, abs=1e-4))
    assert Rate(25, 25).value == 1.0


# ---------------------------------------------------------------- planned schedules, executed


@pytest.fixture(scope="module")
def corridor(tmp_path_factory: pytest.TempPathFactory) -> PlanReport:
    """The paper's corridor task: one paired move (table costs, as the cost tables plan it), as
    the paper runs it: the robots not kept apart (kept apart, r2 passes on another lane)."""
    return plan(CORRIDOR, PlanOptions.of(cache_dir=tmp_path_factory.mktemp("cache"), costs="table", keep_apart=False))


@pytest.mark.slow
def test_mutual_observations_cut_the_worst_error_of_the_landmark_starved_robot(corridor: PlanReport) -> None:
    """The paper's Fig. 3(a) on the corridor: 25 sessions, seeded, so the numbers are exact
    (benchmarks/README.md, "Fig. 3(a)"), the waypoint follower turning at each path node as the
    planned motions do.

    r2 starts in L10, out of every landmark's range; with mutual observations its error
    never exceeds what it starts with, without them it grows along the corridor."""
    assert [a.moves for a in corridor.actions] == [(("r1", "L1", "L10"), ("r2", "L10", "L1"))]
    result = execute(corridor, sessions=25)
    assert result.starved == "r2"
    assert result.reduction("r2") >= 80.0
    assert result.worst(1, "r2") <= float(result.mean_errors(1, "r2")[:2].max()) + 1e-12  # before they meet
    assert result.truncated_sessions == 0
    for robot in ("r1", "r2"):
        assert result.worst(1, robot) < result.worst(2, robot)
    worst = {(c, r): round(result.worst(c, r), 3) for c in (1, 2) for r in ("r1", "r2")}
    assert worst == {(1, "r1"): 0.226, (2, "r1"): 0.42, (1, "r2"): 0.116, (2, "r2"): 0.652}
    # the paper's plan sends the robots head-on through facing doors at once: they touch in
    # every execution (what a separation constraint is for), and without mutual observations
    # the landmark-starved r2 hits walls far more often
    assert result.contact_rate(1) == Rate(25, 25) and result.wall_rate(1) == Rate(1, 25)
    assert result.wall_rate(2, "r2").events > result.wall_rate(2, "r1").events
    for config in (1, 2):  # both start at once and nobody waits
        for schedule in result.schedules[config]:
            assert [(m.robot, m.start, m.wait) for m in schedule.moves] == [("r1", 0.0, 0.0), ("r2", 0.0, 0.0)]
            assert schedule.makespan == max(m.end for m in schedule.moves) > 0.0


@pytest.fixture(scope="module")
def waiting(tmp_path_factory: pytest.TempPathFactory) -> PlanReport:
    """r1 goes from L1 to L10 alone, then r1 and r2 leave L10 together: r2 waits for r1."""
    goals = Goals(visit=(), per_robot=(("r1", ("L2", "L10")), ("r2", ("L1",))))
    options = PlanOptions.of(cache_dir=tmp_path_factory.mktemp("cache"), costs="table", goals=goals, accept_risk=True)
    report = plan(CORRIDOR, options)
    paired = [m for m in report.schedule.moves if m.partner is not None]
    assert paired and report.schedule.waits("r2") > 0.0, f"the planner no longer makes r2 wait: {report.schedule}"
    return report


@pytest.mark.slow
def test_a_planned_wait_is_executed_and_the_makespan_reported(waiting: PlanReport) -> None:
    result = execute(waiting, sessions=2)
    planned = waiting.schedule
    r1_first, r1_pair = planned.timeline("r1")
    for config in (1, 2):
        for schedule in result.schedules[config]:
            first, pair = schedule.timeline("r1")
            (r2,) = schedule.timeline("r2")
            assert (pair.step, r2.step) == (r1_pair.step, r1_pair.step)
            assert pair.start == r2.start == max(first.end, r1_pair.start)  # together, never before the plan
            assert r2.ready == 0.0 and r2.wait == r2.start > 0.0
        assert result.makespans(config).shape == (2,)
        assert np.all(result.makespans(config) > r1_first.end)
    lines = error_summary(result, 2)
    assert f"makespan (until the last robot is done): planned {planned.makespan:.1f} s" in "\n".join(lines)
    assert any(line.startswith("waiting for partners") and "r2 " in line for line in lines)


@pytest.mark.slow
def test_a_moved_up_paired_start_waits_only_for_the_partner(waiting: PlanReport) -> None:
    """With the paired move planned at 0 s, it starts the moment r1 ends its first move."""
    moves = tuple(dataclasses.replace(m, start=0.0) if m.partner else m for m in waiting.schedule.moves)
    report = dataclasses.replace(waiting, schedule=Schedule(waiting.schedule.robots, moves))
    result = execute(report, sessions=1)
    for config in (1, 2):
        first, pair = result.schedules[config][0].timeline("r1")
        (r2,) = result.schedules[config][0].timeline("r2")
        assert pair.start == r2.start == first.end and pair.wait == 0.0 and r2.wait == first.end


@pytest.mark.slow
def test_errors_and_sessions_csv_carry_the_times(waiting: PlanReport) -> None:
    result = execute(waiting, sessions=2)
    rows = list(csv.DictReader(io.StringIO(errors_csv(result, waiting.roadmap))))
    assert list(rows[0])[-3:] == ["planned_t_s", "mean_t_s", "max_t_s"]
    r2 = [r for r in rows if r["robot"] == "r2" and r["config"] == "1"]
    assert r2[0]["planned_t_s"] == r2[0]["mean_t_s"] == "0"
    assert float(r2[1]["mean_t_s"]) > float(next(m for m in waiting.schedule.timeline("r2")).start)
    times = [float(r["mean_t_s"]) for r in r2]
    assert times == sorted(times)
    sessions = list(csv.DictReader(io.StringIO(sessions_csv(result))))
    assert len(sessions) == 2 * 2 * 2  # configurations x sessions x robots
    for row in sessions:
        assert float(row["planned_makespan_s"]) == pytest.approx(waiting.schedule.makespan)
        assert 0.0 < float(row["done_s"]) <= float(row["makespan_s"])
    assert {float(r["wait_s"]) > 0 for r in sessions if r["robot"] == "r2"} == {True}
    assert list(sessions[0])[-2:] == ["wall_hits", "contacts"]
    for row in sessions:
        key, s = (int(row["config"]), row["robot"]), int(row["session"]) - 1
        assert (int(row["wall_hits"]), int(row["contacts"])) == (result.wall_hits[key][s], result.contacts[key][s])


@pytest.mark.slow
def test_the_counts_are_rates_of_executions_in_the_summary(waiting: PlanReport) -> None:
    result = execute(waiting, sessions=2)
    for config in (1, 2):  # two robots: a contact is r1's and r2's
        assert np.array_equal(result.contacts[(config, "r1")], result.contacts[(config, "r2")])
        hit = (result.wall_hits[(config, "r1")] > 0) | (result.wall_hits[(config, "r2")] > 0)
        assert result.wall_rate(config) == Rate(int(hit.sum()), 2)
    for counts in (*result.wall_hits.values(), *result.contacts.values()):
        counts[:] = 0
    # one session of config 1 in which r2 hit a wall at 3 steps: a rate of 1 in 2, r1 still clean
    result.wall_hits[(1, "r2")][1] = 3
    assert result.wall_rate(1) == result.wall_rate(1, "r2") == Rate(1, 2) and result.wall_rate(1, "r1") == Rate(0, 2)
    assert result.contact_rate(2) == Rate(0, 2)
    text = "\n".join(error_summary(result, 2))
    assert "wall hits (executions with a true pose" in text
    assert "  with mutual observations: 1/2 = 50.0% (95% CI 1.3% to 98.7%); per robot r1 0, r2 1" in text
    assert "robot contacts" in text and "  without: 0/2 = 0% (95% CI 0% to 84.2%); per robot r1 0, r2 0" in text


@pytest.mark.slow
def test_sessions_on_worker_processes_are_the_sessions_run_in_one(waiting: PlanReport) -> None:
    one = execute(waiting, sessions=3, workers=1)
    two = execute(waiting, sessions=3, workers=2)
    for key, errors in one.errors.items():
        np.testing.assert_array_equal(errors, two.errors[key])
        np.testing.assert_array_equal(one.planned_nees[key], two.planned_nees[key])
    for key, values in one.filter_nees.items():
        np.testing.assert_array_equal(values, two.filter_nees[key])
    assert one.makespans(1).tolist() == two.makespans(1).tolist()


@pytest.fixture(scope="module")
def lidar_rooms(tmp_path_factory: pytest.TempPathFactory) -> PlanReport:
    """The two rooms off a corridor, the robots with the shipped scenarios' lidar, planned with the
    sensor's own bound (every beam independent), which the simulator's EKF executes."""
    folder = tmp_path_factory.mktemp("lidar")
    text = (ROOT / "configs" / "two-rooms.yaml").read_text()
    scenario = folder / "two-rooms-lidar.yaml"
    scenario.write_text(
        text + "models:\n  range_sensor: {range: 12, beams: 60, sigma_range: 0.03, divergence: 0.01, "
        "localiser: {model: beams}}\n"
    )
    return plan(scenario, PlanOptions.of(cache_dir=folder / "cache"))


@pytest.mark.slow
def test_robots_with_a_lidar_are_localised_as_their_filter_says(lidar_rooms: PlanReport) -> None:
    """True scans ray cast from the true poses, predicted ones from the estimates: the filter's
    position NEES reads as a consistent filter's (a median of about 1.39, about 1.1% of the steps
    beyond 3 sigma), the error agrees with the plan's covariance too, the errors are
    centimetres, and the innovation gate rejects few beams."""
    result = execute(lidar_rooms, sessions=6)
    own, planned = result.own_nees(1), result.nees(1)
    assert 0.7 <= own.median <= 2.2 and own.beyond <= 0.05
    assert 0.7 <= planned.median <= 2.8
    assert max(result.worst(1, r) for r in result.robots) < 0.15  # the start's own uncertainty: 0.1 m
    used, rejected = (sum(result.beams[(1, r)][k] for r in result.robots) for k in (0, 1))
    assert used > 10_000 and rejected / used < 0.05
    lines = "\n".join(error_summary(result, 6))
    assert "position NEES with" in lines and "rejected by the innovation gate" in lines


@pytest.mark.slow
def test_a_lidar_plans_tiny_figures_read_as_figures(lidar_rooms: PlanReport) -> None:
    """With a lidar the bounds fall far below 1e-6 and the stds to centimetres: the summary says
    "< 1e-6" and cm, never an exponent like 6.5e-300, a bound of 0 or "0.00 m"."""
    text = plan_summary(lidar_rooms)
    assert lidar_rooms.risk < 1e-6 and "collision bound: plan < 1e-6 " in text
    assert not re.search(r"\de-(\d{2,}|[7-9])\b", text) and not re.search(r"\b0\.00 m\b|\b0\.0 deg\b", text)
    assert re.search(r"\d\.\d cm", text)


@pytest.mark.slow
def test_each_move_is_held_to_its_own_bound(corridor: PlanReport) -> None:
    """The paper's corridor as planned (one paired move, the robots through each other): every
    execution has the contact during that move; moves.csv lists each move with its executions,
    their 95% interval and the move's bound as planned; the summary names the moves."""
    result = execute(corridor, sessions=4)
    rates = {(robot, step): (hits, touches, bound) for robot, step, hits, touches, bound in result.move_rates(1)}
    assert set(rates) == {("r1", 0), ("r2", 0)}
    for _hits, touches, bound in rates.values():
        assert touches == Rate(4, 4) and bound == pytest.approx(corridor.actions[0].risk[0], abs=1.0)
    rows = list(csv.DictReader(io.StringIO(moves_csv(result))))
    assert len(rows) == 2 * 2 and {r["step"] for r in rows} == {"1"}
    assert all(
        int(r["contact_executions"]) == 4 and float(r["contact_ci_low"]) > 0.3 for r in rows if r["config"] == "1"
    )
    assert any(line.startswith("moves against their bounds") for line in error_summary(result, 4))
    events = list(csv.DictReader(io.StringIO(hits_csv(result))))  # where each contact began, and when
    assert events and all(r["step"] == "1" and r["kind"] in ("wall", "robot") for r in events)
    for config in result.configs:
        for robot in ("r1", "r2"):
            mine = [r for r in events if r["config"] == str(config) and r["robot"] == robot]
            touches = [r for r in mine if r["kind"] == "robot"]
            if config == 1:  # every execution has its contact
                assert {int(r["session"]) for r in touches} == set(range(1, 5))
            assert sum(int(r["steps"]) for r in touches) == int(result.contacts[(config, robot)].sum())
            walls = sum(int(r["steps"]) for r in mine if r["kind"] == "wall")
            assert walls == int(result.wall_hits[(config, robot)].sum())


@pytest.mark.slow
@pytest.mark.parametrize("workers", [1, 2])
def test_past_the_time_limit_only_the_sessions_done_are_kept(waiting: PlanReport, workers: int) -> None:
    """``tmpnav simulate --time-limit``: no time left after planning runs the first session only."""
    result = execute(waiting, sessions=6, workers=workers, seconds=0.0)
    assert all(len(errors) == 1 for errors in result.errors.values())
    again = execute(waiting, sessions=1, workers=workers)
    assert all(np.array_equal(result.errors[k], again.errors[k]) for k in again.errors)  # the same first session
