"""tmpnav's plan against a standard vehicle-routing solver on tmpnav's own single-move table.

    python benchmarks/bench_routing.py -o benchmarks/full/routing [--scenario configs/building-20.yaml]

The yardstick of the building-scale issue: OR-Tools' routing solver (open routes, one vehicle
per robot, guided local search for 20 s) on the single-move cost table of the scenario's
goals. tmpnav plans the same task from an empty cache twice, with table costs (the same
single moves, plus paired moves) and with carried beliefs (the default); every plan --
OR-Tools' routes too -- is also costed as executed, with carried beliefs. Writes
routing.json and summary.md.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tmpnav.attachment.canonical import CanonicalCosts  # noqa: E402
from tmpnav.attachment.carried import CarriedCosts  # noqa: E402
from tmpnav.pipeline import PlanOptions, plan, prepare  # noqa: E402
from tmpnav.results import StageTimes  # noqa: E402
from tmpnav.task.plans import with_origins  # noqa: E402
from tmpnav.task.routing import solve_routes  # noqa: E402


def run(scenario: str, seconds: float) -> dict:
    out: dict = {"scenario": scenario, "or_tools_seconds": seconds}
    with tempfile.TemporaryDirectory() as cache:
        prep = prepare(ROOT / scenario, PlanOptions.of(cache_dir=Path(cache)), StageTimes())
        try:
            canonical = CanonicalCosts(prep.oracle, prep.world, prep.scenario.planner.pair_min_gain)
            singles = canonical.singles(prep.scenario.goals)
            start = time.perf_counter()
            routes = solve_routes(singles, prep.scenario.goals, time_limit=seconds)
            steps = with_origins([((m[0], m[2]),) for m in routes.moves(singles)], singles.start_location)
            carried = CarriedCosts(prep.oracle, canonical)
            out["or_tools"] = {
                "table_cost": routes.cost,
                "executed_cost": carried.plan_cost(steps).total,
                "seconds": time.perf_counter() - start,
                "status": routes.status,
            }
        finally:
            prep.oracle.close()
    for costs in ("table", "carried"):
        with tempfile.TemporaryDirectory() as cache:
            start = time.perf_counter()
            report = plan(ROOT / scenario, PlanOptions.of(cache_dir=Path(cache), costs=costs, search="anytime"))
            out[f"tmpnav_{costs}"] = {
                "planner_cost": report.planner_cost,
                "executed_cost": report.resimulated_cost,
                "seconds": time.perf_counter() - start,
                "stopped": None if report.task.search is None else report.task.search.stopped,
                "pair_steps": sum(len(a.moves) == 2 for a in report.actions),
            }
    return out


def summary(runs: list[dict]) -> str:
    lines = [
        "| scenario | planner | cost on the single-move table | executed cost (carried beliefs) | seconds | notes |",
        "|---|---|---|---|---|---|",
    ]
    for r in runs:
        o = r["or_tools"]
        lines.append(
            f"| {r['scenario']} | OR-Tools routing, guided local search {r['or_tools_seconds']:g} s | "
            f"{o['table_cost']:.2f} | {o['executed_cost']:.2f} | {o['seconds']:.1f} | {o['status']} |"
        )
        for costs in ("table", "carried"):
            t = r[f"tmpnav_{costs}"]
            table_cost = f"{t['planner_cost']:.2f}" if costs == "table" else "-"
            lines.append(
                f"| {r['scenario']} | tmpnav --costs {costs} --search anytime | {table_cost} | "
                f"{t['executed_cost']:.2f} | {t['seconds']:.1f} | stopped: {t['stopped']}; "
                f"{t['pair_steps']} paired steps |"
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--scenario", action="append", default=None)
    parser.add_argument("--seconds", type=float, default=20.0, help="OR-Tools' time limit")
    args = parser.parse_args()
    runs = [run(s, args.seconds) for s in (args.scenario or ["configs/building-20.yaml"])]
    args.output.mkdir(parents=True, exist_ok=True)
    text = summary(runs)
    (args.output / "summary.md").write_text(text)
    (args.output / "routing.json").write_text(json.dumps(runs, indent=1) + "\n")
    print(text)


if __name__ == "__main__":
    main()
