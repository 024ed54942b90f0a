"""``--objective makespan`` against OR-Tools' min-max routing on the same move durations (issue 20).

For each scenario: the cost table's single moves (canonical start states: the moves the
anytime search starts from) with their durations; OR-Tools' routing where each arc costs its
time and a global span cost 100 times larger, the min-max vehicle routing of OR-Tools'
examples, run for ``--seconds`` (guided local search); and ``tmpnav plan --objective makespan
--costs table`` (default search and budget),
whose makespan is the planner's schedule on the same table's durations. Writes
``<out>/makespan.json`` and ``<out>/summary.md``.

    python benchmarks/bench_makespan.py -o benchmarks/full/makespan
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

from tmpnav.attachment.canonical import CanonicalCosts  # noqa: E402
from tmpnav.pipeline import PlanOptions, plan, prepare  # noqa: E402
from tmpnav.results import StageTimes  # noqa: E402
from tmpnav.task.model import TableModel  # noqa: E402
from tmpnav.task.plans import with_origins  # noqa: E402
from tmpnav.task.routing import solve_routes  # noqa: E402

SCENARIOS = ("configs/building-20.yaml", "configs/building-4robots.yaml")


def reference(scenario: str, cache: Path, seconds: float) -> tuple[float, object]:
    """OR-Tools' min-max routes on the table's durations: their makespan, and the table."""
    prep = prepare(ROOT / scenario, PlanOptions.of(cache_dir=cache), StageTimes())
    try:
        canonical = CanonicalCosts(prep.oracle, prep.world, prep.scenario.planner.pair_min_gain)
        singles = canonical.singles(prep.scenario.goals)
        # min-max routing as OR-Tools' examples set it: arcs cost their time, the span 100 times more
        timed = replace(singles, single=dict(singles.duration))
        routes = solve_routes(timed, prep.scenario.goals, time_limit=seconds, span_weight=100.0)
        steps = with_origins([((m[0], m[2]),) for m in routes.moves(singles)], singles.start_location)
        return TableModel(singles).plan_cost(steps).makespan, canonical
    finally:
        prep.oracle.close()


def ours(scenario: str, cache: Path, canonical: object) -> tuple[float, float, float]:
    """tmpnav's plan with the makespan objective: its makespan on the same durations, and time."""
    start = time.perf_counter()
    report = plan(ROOT / scenario, PlanOptions.of(cache_dir=cache, objective="makespan", costs="table"))
    wall = time.perf_counter() - start
    assert report.task.schedule is not None
    return report.task.schedule.makespan, report.schedule.makespan, wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=Path, required=True)
    parser.add_argument("--seconds", type=float, default=60.0, help="OR-Tools' time limit (default 60 s)")
    args = parser.parse_args()
    rows = []
    for scenario in SCENARIOS:
        with tempfile.TemporaryDirectory() as cache:
            ref, canonical = reference(scenario, Path(cache), args.seconds)
            planned, executed, wall = ours(scenario, Path(cache), canonical)
        rows.append(
            {
                "scenario": scenario,
                "or_tools_min_max": ref,
                "tmpnav_makespan_objective": planned,
                "ratio": planned / ref,
                "executed_makespan": executed,
                "tmpnav_seconds": round(wall, 2),
            }
        )
        print(json.dumps(rows[-1]), flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "makespan.json").write_text(json.dumps(rows, indent=1) + "\n")
    lines = [
        "# --objective makespan against OR-Tools' min-max routing\n",
        f"`python benchmarks/bench_makespan.py -o {args.out}` "
        f"({platform.processor() or platform.machine()}, {time.strftime('%Y-%m-%d')}; OR-Tools {args.seconds:g} s)\n",
        "| scenario | OR-Tools min-max [s] | tmpnav --objective makespan [s] | ratio | executed [s] "
        "| tmpnav time [s] |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {Path(r['scenario']).stem} | {r['or_tools_min_max']:.1f} | {r['tmpnav_makespan_objective']:.1f} | "
            f"{r['ratio']:.3f} | {r['executed_makespan']:.1f} | {r['tmpnav_seconds']:.1f} |"
        )
    (args.out / "summary.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
