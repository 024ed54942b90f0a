"""Robots in each other's way (issue 24, item 3): the shipped plans as planned, kept apart by
default, and with siding rooms too.

For every shipped scenario with two or more robots:

1. plans it with ``--no-keep-apart`` (the default cache directory, so remembered plans are
   reused) and counts the conflicts of its re-simulated trajectories with the independent
   checker (:mod:`tmpnav.belief.conflicts`);
2. plans it with the defaults (robots kept apart: waits, detours, split pairs; at most 1.5
   times the objective, tmpnav.attachment.apart.keep_apart) and counts again on the
   report's trajectories, with what was done and the seconds of the ``resimulate`` stage
   that holds the search;
3. resolves the plan as planned once more with siding rooms too (what ``--max-risk`` adds,
   :func:`tmpnav.attachment.passing.resolve_with_sidesteps`), runs the result again from
   scratch and checks it.

Prints a table (conflicts, makespan and executed cost for each) and writes the rows as JSON.

    python benchmarks/bench_conflicts.py [--only corridor two-rooms] [-o out.json]
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
from tmpnav.attachment.passing import resolve_with_sidesteps  # noqa: E402
from tmpnav.belief.conflicts import find_conflicts  # noqa: E402
from tmpnav.pipeline import Execution, PlanOptions, make_oracle, plan  # noqa: E402
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
    """One scenario: as planned, kept apart by default, and with siding rooms."""
    planned = plan(path, PlanOptions.of(keep_apart=False))
    radii = {r.name: r.radius for r in planned.scenario.robots}
    before = find_conflicts(planned.trajectories, radii)
    kept = plan(path)
    after = find_conflicts(kept.trajectories, radii)
    apart = kept.apart
    oracle = make_oracle(planned.scenario, planned.world, planned.roadmap, Execution(executor="serial"))
    try:
        carried = CarriedCosts(oracle, CanonicalCosts(oracle, planned.world, planned.scenario.planner.pair_min_gain))
        start = time.perf_counter()
        res = resolve_with_sidesteps(carried, planned.task.steps, radii)
        sidings_seconds = time.perf_counter() - start
        again = carried.replay(res.plan, res.delays, res.detours)  # run from scratch for the independent check
    finally:
        oracle.close()
    assert again.trajectories is not None
    sidings_left = find_conflicts(again.trajectories, radii)
    weights = planned.scenario.cost
    return {
        "scenario": path.stem,
        "robots": len(planned.scenario.robots),
        "steps": len(planned.task.steps),
        "conflicts_planned": len(before),
        "makespan_planned": planned.schedule.makespan,
        "cost_planned": round(planned.resimulated_cost, 2),
        "conflicts_kept": len(after),
        "makespan_kept": kept.schedule.makespan,
        "cost_kept": round(kept.resimulated_cost, 2),
        "kept": None
        if apart is None
        else {
            "waits": [list(w) for w in apart.waits],
            "detours": [list(d) for d in apart.detours],
            "sidesteps": [list(s) for s in apart.sidesteps],
            "clock_runs": apart.runs,
        },
        "resimulate_seconds": round(kept.times.seconds.get("resimulate", 0.0), 2),
        "left": [(*c.robots, c.t_from, round(c.closest_distance, 2), round(c.required_separation, 2)) for c in after],
        "conflicts_sidings": len(sidings_left),
        "makespan_sidings": again.makespan,
        "cost_sidings": round(sum(again.step_costs(len(res.plan), weights)), 2),
        "sidings_seconds": round(sidings_seconds, 2),
    }


def table(rows: list[dict]) -> str:
    lines = [
        "| scenario | robots | conflicts as planned | kept apart (default) | how | makespan [s] | cost (executed) "
        "| resimulate [s] | with siding rooms | cost | seconds |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        kept = r["kept"]
        how = "-"
        if kept is not None:
            parts = [f"{len(kept['waits'])} waits"] if kept["waits"] else []
            parts += [f"detour {d[1]} step {d[0]} (+{d[2]:.1f} m)" for d in kept["detours"]]
            parts += [f"sidestep {s[0]} via {s[2]}" for s in kept["sidesteps"]]
            how = ", ".join(parts) or "split pair"
        lines.append(
            f"| {r['scenario']} | {r['robots']} | {r['conflicts_planned']} | {r['conflicts_kept']} | {how} "
            f"| {r['makespan_planned']:g} -> {r['makespan_kept']:g} | {r['cost_planned']:g} -> {r['cost_kept']:g} "
            f"| {r['resimulate_seconds']:g} | {r['conflicts_sidings']} | {r['cost_sidings']:g} "
            f"| {r['sidings_seconds']:g} |"
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
