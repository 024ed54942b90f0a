"""The terminal summary: header, one line per plan step on the shared clock, totals with the
makespan and the objective, the robots' time, their beliefs, time per stage."""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np
import pytest

from tmpnav.belief.risk import position_std
from tmpnav.numbers import angle, length, percent, probability
from tmpnav.report.text import plan_summary
from tmpnav.types import PlanStatus

STEP = re.compile(
    r"^\s*(?P<index>\d+)\s+(?P<moves>.+?)\s{2,}(?P<planner>-?\d+\.\d{3})\s+(?P<resim>-?\d+\.\d{3})"
    r"\s+(?P<diff>[+-]\d+\.\d{3})\s+(?P<t0>\d+\.\d)-(?P<t1>\d+\.\d)$"
)
TOTAL = re.compile(
    r"^total \((?P<n>\d+) steps?\)\s+(?P<planner>-?\d+\.\d{3})\s+(?P<resim>-?\d+\.\d{3})\s+(?P<diff>[+-]\d+\.\d{3})"
)

pytestmark = pytest.mark.slow  # every test reads the session's real plan


@pytest.fixture(scope="module")
def lines(plan_report: Any) -> list[str]:
    return plan_summary(plan_report).splitlines()


def test_header(lines: list[str], plan_report: Any) -> None:
    head = lines[0]
    for part in ("three-rooms", "three_rooms.yaml", "encoding mixed", f"planner {plan_report.planner}"):
        assert part in head
    assert plan_report.status.value in head
    assert lines[1].startswith("2 robots, mutual observations on; goals: r1 visits C, B; r2 visits A")


def test_one_line_per_plan_step(lines: list[str], plan_report: Any) -> None:
    steps = [m for m in map(STEP.match, lines) if m]
    assert [int(m["index"]) for m in steps] == [a.index for a in plan_report.actions] == [1, 2]
    expected = ["  &  ".join(f"{r}: {a} -> {b}" for r, a, b in action.moves) for action in plan_report.actions]
    assert [m["moves"] for m in steps] == expected
    for m, action in zip(steps, plan_report.actions, strict=True):
        assert float(m["planner"]) == pytest.approx(action.planner_cost, abs=5e-4)
        assert float(m["resim"]) == pytest.approx(action.resimulated_cost, abs=5e-4)
        assert float(m["diff"]) == pytest.approx(action.resimulated_cost - action.planner_cost, abs=5e-4)
    # each step's window on the shared clock: the test plan's r1 drives to C alone, then r1 and
    # r2 start their paired step together when r1 arrives (r2 waited for it)
    windows = {(m.step + 1, m.robot): (m.start, m.end) for m in plan_report.schedule.moves}
    for m, action in zip(steps, plan_report.actions, strict=True):
        mine = [windows[(action.index, move[0])] for move in action.moves]
        assert (m["t0"], m["t1"]) == (f"{min(w[0] for w in mine):.1f}", f"{max(w[1] for w in mine):.1f}")
    assert steps[0]["t0"] == "0.0" and steps[0]["t1"] == steps[1]["t0"]


def test_totals(lines: list[str], plan_report: Any) -> None:
    total = next(m for m in map(TOTAL.match, lines) if m)
    assert int(total["n"]) == 2
    assert float(total["planner"]) == pytest.approx(plan_report.planner_cost, abs=5e-4)
    assert float(total["resim"]) == pytest.approx(plan_report.resimulated_cost, abs=5e-4)


def test_makespan_and_objective(lines: list[str], plan_report: Any) -> None:
    i = next(i for i, line in enumerate(lines) if line.startswith("total ("))
    makespan = plan_report.schedule.makespan
    assert lines[i].endswith(f"  0.0-{makespan:.1f}")
    assert lines[i + 1] == (
        f"makespan {makespan:.1f} s; objective cost (the sum of action costs): {plan_report.resimulated_cost:.3f}"
    )


def test_an_objective_that_prices_time_and_a_planner_that_saw_another_schedule(plan_report: Any) -> None:
    planner = dataclasses.replace(plan_report.scenario.planner, objective="weighted")
    scenario = dataclasses.replace(plan_report.scenario, planner=planner)
    task = plan_report.task
    slower = dataclasses.replace(
        task.schedule, moves=tuple(dataclasses.replace(m, end=m.end + 2.0) for m in task.schedule.moves)
    )
    report = dataclasses.replace(plan_report, scenario=scenario, task=dataclasses.replace(task, schedule=slower))
    lines = plan_summary(report).splitlines()
    m_t, makespan = scenario.cost.M_T, plan_report.schedule.makespan
    line = next(line for line in lines if line.startswith("makespan "))
    planned = plan_report.planner_cost + m_t * (makespan + 2.0)
    value = plan_report.resimulated_cost + m_t * makespan
    assert line == (
        f"makespan {makespan:.1f} s (planner's schedule: {makespan + 2.0:.1f} s); objective weighted "
        f"(cost + {m_t:g} per s of makespan): planner {planned:.3f}, re-simulated {value:.3f}"
    )
    assert any(line.startswith("lower bound on the objective: ") for line in lines)


HEAD = "robot  rooms    busy   waits  idle [s]  travelled  pos. std max / end  heading std  collision bound"


def test_robots_on_the_shared_clock(lines: list[str], plan_report: Any) -> None:
    i = lines.index(HEAD)
    rows = [line.split() for line in lines[i + 1 : i + 3]]
    schedule = plan_report.schedule
    for row, robot in zip(rows, ["r1", "r2"], strict=True):
        assert row[0] == robot and int(row[1]) == len(schedule.timeline(robot))
        busy, waits, idle = (float(x) for x in row[2:5])
        assert busy == pytest.approx(schedule.busy(robot), abs=0.05)
        assert waits == pytest.approx(schedule.waits(robot), abs=0.05)
        assert idle == pytest.approx(schedule.idle(robot), abs=0.05)
    assert float(rows[1][3]) > 0 and float(rows[0][4]) > 0  # r2 waits for r1; r1 is idle at the end
    assert lines[i + 3].startswith("(busy: driving, in control steps of 0.5 s; idle: ")


def test_beliefs_per_robot(lines: list[str], plan_report: Any) -> None:
    i = lines.index(HEAD)
    rows = lines[i + 1 : i + 3]
    assert [r.split()[0] for r in rows] == ["r1", "r2"]
    for row, robot in zip(rows, ["r1", "r2"], strict=True):
        travelled, pos_std, heading, bound = re.split(r"\s{2,}", row.strip())[5:]  # cells: two spaces apart
        assert re.fullmatch(r"\d+\.\d m", travelled), row
        stds = [float(position_std(np.array(s.cov))) for s in plan_report.trajectories[robot]]  # sqrt(lambda_max)
        assert pos_std == f"{length(max(stds))} / {length(stds[-1])}"
        assert heading == angle(math.sqrt(plan_report.trajectories[robot][-1].cov[2][2]))
        risks = [p for a in plan_report.actions for (r, _, _), p in zip(a.moves, a.risk, strict=True) if r == robot]
        assert bound == probability(max(risks))
    # figures an engineer can believe: no exponent below 1e-6, no std rounded to nothing
    assert not re.search(r"e-(\d\d|[7-9])\b", "\n".join(lines)) and "0.00 m" not in "\n".join(lines)
    # the plan's collision bound and the conflicts in one line under the table
    assert lines[i + 4].startswith("(pos. std: along the widest axis")
    assert lines[i + 5].startswith("collision bound: plan ")
    assert "robots in each other's way: " in lines[i + 5]


def test_times_and_cache(lines: list[str], plan_report: Any) -> None:
    i = next(i for i, line in enumerate(lines) if line.startswith("time [s]  "))
    names, values = lines[i].split()[2:], lines[i + 1].split()
    assert names == ["roadmap", "oracle", "encode", "planner", "resimulate", "other", "total", "(load)"]
    seconds = plan_report.times.seconds
    for name, value in zip(names, values, strict=True):
        assert float(value) == pytest.approx(seconds[name.strip("()")], abs=5e-3)
    cache_line = lines[i + 2]
    hits, misses = plan_report.cache.hits, plan_report.cache.misses
    assert re.fullmatch(rf"cache \(.+\): roadmap grown; move costs: {hits} from cache, {misses} computed", cache_line)


def test_the_cache_line_says_one_thing(plan_report: Any) -> None:
    """A cost table read from the cache and costs computed after it are one story, not a hit
    ratio next to "cost table from cache"."""

    def line(**changes: Any) -> str:
        cache = dataclasses.replace(plan_report.cache, **changes)
        return plan_summary(dataclasses.replace(plan_report, cache=cache)).splitlines()[-1]

    warm = line(hits=0, misses=0, roadmap_hit=True, table_hit=True, plan_hit=True)
    assert warm.endswith(
        ": roadmap from cache; move costs: cost table from cache; task plan from cache (--replan runs the planner)"
    )
    more = line(hits=427, misses=12097, roadmap_hit=True, table_hit=True)
    assert more.endswith(
        ": roadmap from cache; move costs: cost table from cache, then 427 more from cache and 12097 computed"
    )
    assert "%" not in more and "hit" not in more


def test_plain_text(plan_report: Any) -> None:
    text = plan_summary(plan_report)
    assert "\x1b[" not in text  # no colours
    cache_dir = str(plan_report.cache.directory)
    # fits a terminal, except for lines with paths (scenario file, cache directory)
    assert max(len(line) for line in text.splitlines() if cache_dir not in line and ".yaml" not in line) <= 100
    assert not text.endswith("\n")


def test_a_plan_is_either_proved_optimal_or_has_a_gap_never_both(plan_report: Any, kept_report: Any) -> None:
    """The bound's line says "proved optimal" or a gap, never both: a plan kept apart after its
    search met the bound once read "gap 22.46% ... the plan searched: proved optimal"."""
    for report in (plan_report, kept_report):
        (line,) = [line for line in plan_summary(report).splitlines() if line.startswith("lower bound")]
        assert ("proved optimal" in line) != ("gap " in line), line


def test_satisficing_and_cache_off(plan_report: Any) -> None:
    other = dataclasses.replace(
        plan_report,
        task=dataclasses.replace(plan_report.task, status=PlanStatus.SOLVED_SATISFICING, bound=None),
        cache=dataclasses.replace(plan_report.cache, enabled=False, hits=0, warnings=("cache is read-only",)),
    )
    text = plan_summary(other)
    assert "solved-satisficing (not proven optimal)" in text.splitlines()[0]  # no bound to say how far
    assert "cache: off (" in text
    assert "cache warning: cache is read-only" in text


def test_robots_kept_apart(kept_report: Any) -> None:
    """By default robots in each other's way are kept apart after planning: the summary says
    how and what it cost against the plan as planned; the status, the bound's gap and its verdict
    are the plan kept apart's, one vocabulary (the plan searched met its bound, the plan kept
    apart has a gap: the line says so and proves nothing); no conflict is left."""
    lines = plan_summary(kept_report).splitlines()
    apart = kept_report.apart
    assert apart is not None and (apart.conflicts_before, apart.conflicts_left) == (1, 0)
    assert lines[0].endswith(", solved-satisficing")
    bound = kept_report.task.bound
    assert bound is not None and not bound.proved_optimal
    (line,) = [line for line in lines if line.startswith("lower bound")]
    assert line.endswith(
        f"; gap {percent(bound.gap)}, all of it from keeping the robots apart (the plan as searched met the bound)"
    )
    assert any(line.endswith("robots in each other's way: none") for line in lines)
    i = next(i for i, line in enumerate(lines) if line.startswith("kept apart: 1 -> 0 conflicts by "))
    cost = kept_report.resimulated_cost - apart.cost_before
    assert f"cost {cost:+.3f}, makespan " in " ".join(lines[i : i + 2])
    assert kept_report.task.status == PlanStatus.SOLVED_SATISFICING
