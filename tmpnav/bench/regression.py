"""Regression runs: a few shipped scenarios whose plans and costs are recorded in benchmarks/regression/.

    python -m tmpnav.bench.regression            # check: exit 1 if a plan or cost changed
    python -m tmpnav.bench.regression --update   # rewrite the baseline on purpose (make regression-update)

The baseline lives in the source checkout (benchmarks/regression/), not in the package:
this is a developer's check, run from the checkout.

A recorded plan is the sequence of moves of every step; costs are compared to a relative
tolerance of 1e-6 (the same machine type gives the same bits; the tolerance only absorbs
a different BLAS). Plans are computed without any cache, so the baseline checks the whole
pipeline, not the cache. The anytime search's budget is work, so its plan is the same on any
machine; a plan that a time cap cut short (plan.json's ``search.capped``) is the machine's,
and fails the run instead of being compared (or recorded).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tmpnav import shipped
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.types import Goals

BASELINE = Path(__file__).resolve().parents[2] / "benchmarks" / "regression"
RTOL = 1e-6


@dataclass(frozen=True)
class Case:
    """A recorded plan: a shipped scenario (``configs/NAME.yaml``), its goals and encoding."""

    name: str
    scenario: str
    visit: tuple[str, ...] | None = None  # replaces the scenario's goals when given
    encoding: str | None = None
    why: str = ""
    costs: str = "carried"
    search: str | None = None  # None: auto
    work_budget: int | None = None  # anytime: a budget it never reaches, so the plan is the converged one
    objective: str | None = None  # None: the default (weighted); "cost": the paper's sum, the plans of before
    keep_apart: bool | None = None  # None: the default (robots kept apart); False: the plan as planned
    range_sensor: bool = True  # False: without the scenario's range sensor (the paper's model)
    #: checked by the test suite too; False: only by ``make regression`` (a case that takes most
    #: of a minute of the suite's time)
    suite: bool = True


CASES = (
    # the paper's model: table costs, the exact search, the sum of action costs (objective
    # "cost"), robots not kept apart; recorded before carried costs became the default, and the planner's plans and
    # costs have not changed since. Their re-simulated costs are the plans run with all robots
    # at once (since schedules): those of the paired moves (fig2, odd-rooms-paper) are as before.
    Case(
        "fig2",
        "configs/corridor.yaml",
        why="the paper's Fig. 2 swap: one paired move",
        costs="table",
        search="exact",
        objective="cost",
        keep_apart=False,
    ),
    Case(
        "odd-rooms",
        "configs/corridor-2robots.yaml",
        ("L2", "L5", "L9"),
        why="an odd number of rooms, mixed",
        costs="table",
        search="exact",
        objective="cost",
        keep_apart=False,
    ),
    Case(
        "odd-rooms-paper",
        "configs/corridor-2robots.yaml",
        ("L2", "L5", "L9"),
        "paper",
        why="the same with the paper's encoding: the extra visit",
        costs="table",
        search="exact",
        objective="cost",
        keep_apart=False,
        suite=False,  # 30-50 s: every pair of moves between the corridor's ten rooms (82,944) into ENHSP
    ),
    Case(
        "three-robots",
        "configs/corridor-3robots.yaml",
        why="three robots on the corridor",
        costs="table",
        search="exact",
        objective="cost",
        keep_apart=False,
    ),
    Case(
        "ros-map",
        "configs/office-ros.yaml",
        why="a ROS map_server office, three robots",
        costs="table",
        search="exact",
        objective="cost",
        keep_apart=False,
        range_sensor=False,  # the paper's model: without the lidar the scenario carries
    ),
    # the defaults: carried-over beliefs, the search auto chooses, the weighted objective (the
    # team on one clock, time priced): recorded again when schedules came
    Case(
        "fig2-carried",
        "configs/corridor.yaml",
        why="the Fig. 2 swap with carried beliefs: the unfolded search's two single moves, kept apart, cost more "
        "than the paired move the anytime search then finds with every plan priced as executed",
    ),
    Case(
        "sparse-carried",
        "configs/sparse-warehouse.yaml",
        ("P1", "P3", "P5", "P8"),
        why="four places of the landmark-sparse hall, three robots: the unfolded search",
    ),
    Case(
        "sparse-anytime",
        "configs/sparse-warehouse.yaml",
        ("P1", "P2", "P3", "P4", "P5", "P6", "P7"),
        why="seven places of the landmark-sparse hall: the anytime search with carried beliefs, to convergence",
        work_budget=10_000,
    ),
)


def run_case(case: Case) -> dict[str, Any]:
    """Plan a case without any cache; the plan and costs as they are recorded."""
    goals = Goals(visit=case.visit, per_robot=()) if case.visit else None
    scenario = shipped.configs_dir() / Path(case.scenario).name
    options = PlanOptions.of(
        encoding=case.encoding,
        goals=goals,
        use_cache=False,
        costs=case.costs,
        search=case.search,
        work_budget=case.work_budget,
        objective=case.objective,
        keep_apart=case.keep_apart,
        range_sensor=None if case.range_sensor else False,
        accept_risk=True,  # the plan is recorded whatever it leaves
    )
    report = plan(scenario, options)
    return {
        "name": case.name,
        "scenario": case.scenario,
        "why": case.why,
        "encoding": report.encoding,
        "planner": report.planner,
        "costs": report.scenario.planner.costs,
        "search": report.scenario.planner.search,
        "objective": report.scenario.planner.objective,
        "makespan": report.schedule.makespan,
        "goals": list(report.scenario.goals.all_rooms),
        "steps": [[list(m) for m in a.moves] for a in report.actions],
        "goal_nodes": [list(a.goal_nodes) for a in report.actions],
        "planner_cost": report.planner_cost,
        "resimulated_cost": report.resimulated_cost,
        "capped": list(report.task.search.capped) if report.task.search is not None else [],
    }


def compare(recorded: dict[str, Any], now: dict[str, Any]) -> list[str]:
    """What changed, in words (empty when the run matches its baseline); a plan a time cap cut
    short is not compared: it depends on the machine's speed."""
    if now.get("capped"):
        return [f"not compared: {', '.join(now['capped'])} cut the search short (a plan of this machine's speed)"]
    diffs = []
    if recorded["steps"] != now["steps"]:
        diffs.append(f"plan changed: {recorded['steps']} -> {now['steps']}")
    for key in ("planner_cost", "resimulated_cost"):
        if not math.isclose(recorded[key], now[key], rel_tol=RTOL):
            diffs.append(f"{key} changed: {recorded[key]!r} -> {now[key]!r}")
    return diffs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--update", action="store_true", help="rewrite the recorded baseline")
    parser.add_argument("cases", nargs="*", help="case names (default: all)")
    args = parser.parse_args()
    if not BASELINE.parent.is_dir():
        sys.exit(f"error: {BASELINE} not found: run the regression check from a source checkout")
    failed = False
    for case in CASES:
        if args.cases and case.name not in args.cases:
            continue
        now = run_case(case)
        path = BASELINE / f"{case.name}.json"
        if args.update and now["capped"]:
            print(f"{case.name}: not recorded: {', '.join(now['capped'])} cut the search short")
            failed = True
            continue
        if args.update:
            BASELINE.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps({k: v for k, v in now.items() if k != "capped"}, indent=1) + "\n")
            print(f"{case.name}: recorded {len(now['steps'])} steps, cost {now['planner_cost']:.6f}")
            continue
        if not path.exists():
            print(f"{case.name}: no baseline; run `make regression-update`")
            failed = True
            continue
        diffs = compare(json.loads(path.read_text()), now)
        print(f"{case.name}: {'ok' if not diffs else 'CHANGED: ' + '; '.join(diffs)}")
        failed |= bool(diffs)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
