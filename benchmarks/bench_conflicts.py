"""Robots in each other's way (issue 24, item 3): conflicts of the shipped plans before and after waits.

For every shipped scenario with two or more robots, plans with the defaults (the default cache
directory, so remembered plans are reused), checks the re-simulated trajectories with the
independent checker (:mod:`tmpnav.belief.conflicts`), resolves the conflicts by waits
(:func:`tmpnav.attachment.conflicts.resolve_conflicts`) and checks the resolved run again.
Where waits leave a conflict, resolves again allowing sidesteps
(:func:`~tmpnav.attachment.conflicts.resolve_with_sidesteps`) and checks that plan, run again
from scratch, with the independent checker. Prints a table: conflicts as planned, after waits
(clock runs and seconds), after sidesteps, the sidesteps and waits of the final plan, its
makespan and executed cost against the planned ones, and the sidestep search's runs and seconds.

    python benchmarks/bench_conflicts.py [--only corridor warehouse-2robots] [-o out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tmpnav.attachment.canonical import CanonicalCosts  # noqa: E402
from tmpnav.attachment.carried import CarriedCosts  # noqa: E402
from tmpnav.attachment.conflicts import resolve_conflicts, resolve_with_sidesteps  # noqa: E402
from tmpnav.belief.conflicts import find_conflicts  # noqa: E402
from tmpnav.pipeline import Execution, make_oracle, plan  # noqa: E402
from tmpnav.scenario import load_partial  # noqa: E402
from tmpnav.shipped import scenarios  # noqa: E402


def team_configs(only: list[str] | None) -> list[Path]:
    """The shipped scenarios with two or more robots (those named by ``only``, when given)."""
    found = []
    for path in scenarios():
        scenario, _ = load_partial(path)
        if scenario is not None and len(scenario.robots) >= 2 and (not only or path.stem in only):
            found.append(path)
    return found


def measure(path: Path) -> dict:
    """One scenario: plan, check, resolve, check again."""
    start = time.perf_counter()
    report = plan(path)
    planned = time.perf_counter() - start
    radii = {r.name: r.radius for r in report.scenario.robots}
    before = find_conflicts(report.trajectories, radii)
    oracle = make_oracle(report.scenario, report.world, report.roadmap, Execution(executor="serial"))
    try:
        carried = CarriedCosts(oracle, CanonicalCosts(oracle, report.world, report.scenario.planner.pair_min_gain))
        start = time.perf_counter()
        waits = resolve_conflicts(carried, report.task.steps, radii)
        seconds = time.perf_counter() - start
        res = resolve_with_sidesteps(carried, report.task.steps, radii)
        sidestep_seconds = time.perf_counter() - start - seconds
        again = carried.replay(res.plan, res.delays)  # run from scratch for the independent check
    finally:
        oracle.close()
    assert again.trajectories is not None
    after = find_conflicts(again.trajectories, radii)
    left = [(*c.robots, c.t_from, c.t_to, round(c.closest_distance, 2), round(c.required_separation, 2)) for c in after]
    steps, weights = len(report.task.steps), report.scenario.cost
    return {
        "scenario": path.stem,
        "robots": len(report.scenario.robots),
        "steps": steps,
        "conflicts_before": len(before),
        "conflicts_after_waits": len(waits.conflicts_left),
        "conflicts_after": len(after),
        "sidesteps": len(res.plan) - steps,
        "worst_before": min((c.closest_distance - c.required_separation for c in before), default=None),
        "left": left,
        "waits": len(res.delays),
        "wait_seconds": round(sum(res.delays.values()), 2),
        "makespan_before": report.schedule.makespan,
        "makespan_after": res.run.makespan,
        "cost_before": round(report.resimulated_cost, 2),
        "cost_after": round(sum(res.run.step_costs(len(res.plan), weights)), 2),
        "runs": waits.iterations,
        "resolve_seconds": round(seconds, 2),
        "sidestep_runs": res.iterations,
        "sidestep_seconds": round(sidestep_seconds, 2),
        "plan_seconds": round(planned, 1),
    }


def table(rows: list[dict]) -> str:
    lines = [
        "| scenario | robots | steps | conflicts | after waits | runs, s | after sidesteps | sidesteps "
        "| waits (s) | makespan [s] | cost (executed) | runs, s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scenario']} | {r['robots']} | {r['steps']} | {r['conflicts_before']} "
            f"| {r['conflicts_after_waits']} | {r['runs']}, {r['resolve_seconds']:g} "
            f"| {r['conflicts_after']} | {r['sidesteps']} | {r['waits']} ({r['wait_seconds']:g}) "
            f"| {r['makespan_before']:g} -> {r['makespan_after']:g} | {r['cost_before']:g} -> {r['cost_after']:g} "
            f"| {r['sidestep_runs']}, {r['sidestep_seconds']:g} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", help="scenario names (file stems) to run")
    parser.add_argument("-o", "--out", type=Path, help="write the rows as JSON here")
    args = parser.parse_args()
    rows = []
    for path in team_configs(args.only):
        rows.append(measure(path))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    print(table(rows))
    if args.out is not None:
        args.out.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
