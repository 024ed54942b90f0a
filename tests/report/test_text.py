"""The terminal summary: header, one line per plan step, totals, beliefs, time per stage."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

import pytest

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
    assert steps[0]["t0"] == "0.0" and steps[0]["t1"] == steps[1]["t0"]


def test_totals(lines: list[str], plan_report: Any) -> None:
    total = next(m for m in map(TOTAL.match, lines) if m)
    assert int(total["n"]) == 2
    assert float(total["planner"]) == pytest.approx(plan_report.planner_cost, abs=5e-4)
    assert float(total["resim"]) == pytest.approx(plan_report.resimulated_cost, abs=5e-4)


def test_beliefs_per_robot(lines: list[str]) -> None:
    start = next(i for i, line in enumerate(lines) if line.startswith("robot "))
    rows = lines[start + 1 : start + 3]
    assert [r.split()[0] for r in rows] == ["r1", "r2"]
    for row in rows:
        assert re.search(r"\d+\.\d m\s+\d+\s+\d+\.\d{2} m\s+\d+\.\d{2} m\s+\d+\.\d deg$", row), row


def test_times_and_cache(lines: list[str], plan_report: Any) -> None:
    i = next(i for i, line in enumerate(lines) if line.startswith("time [s]  "))
    names, values = lines[i].split()[2:], lines[i + 1].split()
    assert names == ["roadmap", "oracle", "encode", "planner", "resimulate", "total", "(load)"]
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


def test_satisficing_and_cache_off(plan_report: Any) -> None:
    other = dataclasses.replace(
        plan_report,
        task=dataclasses.replace(plan_report.task, status=PlanStatus.SOLVED_SATISFICING),
        cache=dataclasses.replace(plan_report.cache, enabled=False, hits=0, warnings=("cache is read-only",)),
    )
    text = plan_summary(other)
    assert "solved-satisficing (not proven optimal)" in text.splitlines()[0]
    assert "cache: off (" in text
    assert "cache warning: cache is read-only" in text
