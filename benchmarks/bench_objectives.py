"""The objectives on the shipped buildings: cost, makespan and who does how much (issue 20).

For each scenario, plans with ``--objective cost`` (the paper's sum), ``weighted`` with several
``cost.M_T`` and ``makespan``, each in a fresh process-free run with a cold cache, the default
search and budget; records the summed cost (as executed), the makespan, the rooms and busy
time of each robot and the planning time. Writes ``<out>/objectives.json`` and
``<out>/summary.md``.

    python benchmarks/bench_objectives.py -o benchmarks/full/objectives
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tmpnav.pipeline import PlanOptions, load_world, plan  # noqa: E402

SCENARIOS = ("configs/corridor-2robots.yaml", "configs/building-20.yaml", "configs/building-4robots.yaml")
RUNS = (("cost", None), ("weighted", 0.25), ("weighted", 0.5), ("weighted", 1.0), ("weighted", 2.0), ("makespan", None))


def run(scenario: str, objective: str, m_t: float | None) -> dict:
    sc, world = load_world(ROOT / scenario)
    if m_t is not None:
        sc = replace(sc, cost=replace(sc.cost, M_T=m_t))
    with tempfile.TemporaryDirectory() as cache:
        start = time.perf_counter()
        report = plan(sc.source, PlanOptions.of(cache_dir=Path(cache), objective=objective), loaded=(sc, world))
        wall = time.perf_counter() - start
    s = report.schedule
    return {
        "scenario": scenario,
        "objective": objective,
        "M_T": m_t,
        "cost": report.resimulated_cost,
        "planner_cost": report.planner_cost,
        "makespan": s.makespan,
        "rooms": {r: len(s.timeline(r)) for r in s.robots},
        "busy": {r: round(s.busy(r), 1) for r in s.robots},
        "seconds": round(wall, 2),
        "stopped": report.task.search.stopped if report.task.search else None,
        "search": report.task.search.mode if report.task.search else None,
    }


def summary(rows: list[dict]) -> str:
    lines = [
        "| scenario | objective | M_T | cost (executed) | makespan [s] | rooms per robot | time [s] | stopped |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        rooms = ", ".join(f"{k} {v}" for k, v in r["rooms"].items())
        m_t = "" if r["M_T"] is None else f"{r['M_T']:g}"
        lines.append(
            f"| {Path(r['scenario']).stem} | {r['objective']} | {m_t} | {r['cost']:.1f} | {r['makespan']:.1f} | "
            f"{rooms} | {r['seconds']:.1f} | {r['stopped']} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=Path, required=True)
    parser.add_argument("--scenario", action="append", help="scenario (repeat; default: the three buildings)")
    args = parser.parse_args()
    rows = []
    for scenario in args.scenario or SCENARIOS:
        for objective, m_t in RUNS:
            rows.append(run(scenario, objective, m_t))
            print(json.dumps(rows[-1]), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "objectives.json").write_text(json.dumps(rows, indent=1) + "\n")
    machine = f"{platform.processor() or platform.machine()}, {platform.system()}"
    command = f"python benchmarks/bench_objectives.py -o {args.out}"
    head = f"# Objectives\n\n`{command}` ({machine}, {time.strftime('%Y-%m-%d')})\n\n"
    (args.out / "summary.md").write_text(head + summary(rows))


if __name__ == "__main__":
    main()
