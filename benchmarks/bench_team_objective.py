"""The default objective against ``--objective makespan`` on team scenarios: does the team work?

For each scenario, plans with each objective (the default search and budget, one shared cache,
warm: run it twice and keep the second run's lines; no plan remembered from a run before) and records the makespan, the
summed cost as executed, each robot's moves, the robots that never move though some goal is
theirs to do (idle all shift), and the lower bound. One JSON line per run on stdout and in
``<out>/team_objective.jsonl``; ``--table`` prints the markdown table of benchmarks/README.md
from that file.

    python benchmarks/bench_team_objective.py -o benchmarks/shift configs/depot-jobs.yaml \
        benchmarks/shift/warehouse-far-dock.yaml
    python benchmarks/bench_team_objective.py -o benchmarks/shift --table
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tmpnav.pipeline import PlanOptions, plan  # noqa: E402


def run(scenario: Path, objective: str | None, cache: Path) -> dict:
    """One plan of ``scenario`` with ``objective`` (None: the scenario's own or the default)."""
    start = time.perf_counter()
    # replan: a plan remembered from a run cut short by a cold cache is not what this measures
    report = plan(scenario, PlanOptions.of(cache_dir=cache, objective=objective, replan=True))
    wall = time.perf_counter() - start
    s, goals = report.schedule, report.scenario.goals
    moves = {r: len(s.timeline(r)) for r in s.robots}
    could = {r for r in s.robots if any(goals.may_visit(r, x) for x in goals.required)}
    bound = report.task.bound
    return {
        "scenario": str(scenario),
        "asked": objective,
        "objective": report.scenario.planner.objective,
        "makespan": s.makespan,
        "cost": round(report.resimulated_cost, 3),
        "moves": moves,
        "idle": sorted(r for r, n in moves.items() if n == 0 and r in could),
        "bound": None if bound is None else bound.value,
        "gap": None if bound is None else round(bound.gap, 4),
        "stopped": report.task.search.stopped if report.task.search else None,
        "seconds": round(wall, 1),
    }


def table(rows: list[dict]) -> str:
    """Per scenario and objective asked: makespan (and against ``makespan``'s), idle robots."""
    by: dict[str, dict[str, dict]] = {}
    for r in rows:
        by.setdefault(r["scenario"], {})[r["asked"] or "default"] = r
    lines = [
        "| scenario | objective | makespan [s] | / `makespan`'s | cost | robots that never move |",
        "|---|---|---|---|---|---|",
    ]
    for name, runs in by.items():
        best = runs.get("makespan")
        for asked, r in runs.items():
            ratio = f"{r['makespan'] / best['makespan']:.3f}" if best and best["makespan"] > 0 else "-"
            shown = f"default ({r['objective']})" if asked == "default" else asked
            lines.append(
                f"| {Path(name).stem} | {shown} | {r['makespan']:.1f} | {ratio} | {r['cost']:.1f} | "
                f"{', '.join(r['idle']) or 'none'} |"
            )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=Path, required=True)
    parser.add_argument("scenarios", nargs="*", type=Path)
    parser.add_argument(
        "--objective",
        action="append",
        help="default, weighted, cost or makespan (repeat; default: default and makespan)",
    )
    parser.add_argument("--cache-dir", type=Path, default=Path.home() / ".cache" / "tmpnav")
    parser.add_argument("--table", action="store_true", help="print the table of the recorded runs")
    args = parser.parse_args()
    path = args.out / "team_objective.jsonl"
    if args.table:
        print(table([json.loads(line) for line in path.read_text().splitlines() if line.strip()]))
        return
    args.out.mkdir(parents=True, exist_ok=True)
    objectives = [None if o == "default" else o for o in (args.objective or ["default", "makespan"])]
    for scenario in args.scenarios:
        for objective in objectives:
            row = run(scenario, objective, args.cache_dir)
            print(json.dumps(row), flush=True)
            with path.open("a") as f:
                f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
