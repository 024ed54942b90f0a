"""An independent reference for the task level (issue 42, item 5): on generated 2-robot offices,
tmpnav's plan against the exact optimum of the same cost table computed here by Held-Karp.

    python benchmarks/bench_references.py --rooms 6,8,10,12 --seeds 5 -o benchmarks/references

Each instance is `benchmarks/families.py office` (2 robots, seeded), planned by `tmpnav.pipeline.plan`
with `costs=table, objective=cost, encoding=single`: every move is one robot's, its cost the
table's, and the plan's cost the sum of its moves'. The reference takes that same table
(`report.table`) and solves the problem with no search of tmpnav's: for each robot, Held-Karp's
dynamic programme over subsets gives the cheapest open path from its start through every subset
of the goal rooms; the optimum is the least, over the splits of the rooms between the two robots,
of the two paths' costs (a room a robot starts in is visited), on every single move of the
roadmap (the oracle computes those the search never asked for). With `--objective makespan`
the same programme runs on the moves' durations and the split's value is the longer path: the
exact least makespan of single moves without waits (stronger than OR-Tools' min-max routing,
which is a heuristic), against the plan's makespan as the planner saw it. tmpnav's plan is optimal when
its cost equals it; its gap says how far it is when not. With `--objective makespan` the
issue's own reference is there too: OR-Tools' min-max routing on the same table's durations
(its guided local search with the span's cost, :data:`MINMAX_SOLUTIONS` solutions, no other
stop), the longer of its two routes' driving times. Writes `references.csv` and
`references.txt` (`references-makespan.*`) to -o.
"""

from __future__ import annotations

import argparse
import csv
import math
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from families import office, write  # noqa: E402

from tmpnav.pipeline import PlanOptions, make_oracle, plan  # noqa: E402
from tmpnav.planning.run import span_weight_of  # noqa: E402
from tmpnav.planning.table import full_table  # noqa: E402
from tmpnav.results import PlanReport, StageTimes  # noqa: E402
from tmpnav.task.routing import solve_routes  # noqa: E402
from tmpnav.types import RISK_PENALTY, CostTable, Goals  # noqa: E402

#: OR-Tools' solutions for the min-max reference (the anytime search's first routes stop after 500)
MINMAX_SOLUTIONS = 2000


def held_karp(cost: np.ndarray) -> np.ndarray:
    """best[S]: the least cost of an open path from the start through exactly the rooms of subset
    S (a bit mask over n rooms), for ``cost`` (n + 1, n): row 0 from the start, row 1 + i from room
    i, column j into room j (inf where there is no move)."""
    n = cost.shape[1]
    full = 1 << n
    dp = np.full((full, n), math.inf)
    for j in range(n):
        dp[1 << j, j] = cost[0, j]
    between = cost[1:, :]  # (n, n): room i -> room j
    for s in range(1, full):
        row = dp[s]
        if not np.isfinite(row).any():
            continue
        reach = np.min(row[:, None] + between, axis=0)  # into each room k, from the path's last room
        for k in range(n):
            if not (s >> k) & 1 and reach[k] < dp[s | (1 << k), k]:
                dp[s | (1 << k), k] = reach[k]
    best = dp.min(axis=1)
    best[0] = 0.0
    return best


def optimum(table: CostTable, rooms: list[str], objective: str = "cost") -> float:
    """The least total cost (``objective`` cost) or the least makespan (``makespan``: the longer
    robot's driving time, no waits) of single moves by which the table's two robots visit ``rooms``."""
    values = table.single if objective == "cost" else table.duration
    robots = list(table.robots)
    left = [x for x in rooms if x not in table.start_location.values()]  # visited by starting there
    n = len(left)
    bests = []
    for r in robots:
        start = table.start_location[r]
        cost = np.full((n + 1, n), math.inf)
        for j, to in enumerate(left):
            cost[0, j] = values.get((r, start, to), math.inf)
            for i, origin in enumerate(left):
                if i != j:
                    cost[1 + i, j] = values.get((r, origin, to), math.inf)
        bests.append(held_karp(cost))
    full = (1 << n) - 1
    masks = np.arange(1 << n)
    if len(robots) == 1:
        return float(bests[0][full])
    assert len(robots) == 2, "the reference is for two robots"
    join = np.add if objective == "cost" else np.maximum
    return float(np.min(join(bests[0][masks], bests[1][full ^ masks])))


def minmax(table: CostTable, goals: Goals, span_weight: float) -> float:
    """OR-Tools' min-max routing of the table's robots through the goals: the longer route's
    driving time (the durations Held-Karp's makespan sums) after :data:`MINMAX_SOLUTIONS` solutions."""
    routes = solve_routes(table, goals, 600.0, solution_limit=MINMAX_SOLUTIONS, span_weight=span_weight)
    busy = dict.fromkeys(table.robots, 0.0)
    for m in routes.moves(table):
        busy[m[0]] += table.duration[m]
    return max(busy.values())


def whole_table(report: PlanReport, options: PlanOptions) -> CostTable:
    """Every single move of the plan's roadmap (the anytime search's table holds only those it
    asked for), from the same oracle and cache: the costs the plan saw, and the others."""
    oracle = make_oracle(report.scenario, report.world, report.roadmap, options.execution)
    return full_table(report.scenario, report.world, oracle, StageTimes())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rooms", default="6,8,10,12")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--objective", choices=("cost", "makespan"), default="cost")
    ap.add_argument(
        "--without-route-edits", action="store_true", help="the anytime search without its edits between routes"
    )
    ap.add_argument("-o", "--output", type=Path, required=True)
    args = ap.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    if args.without_route_edits:  # the search as it was before its edits between routes
        import tmpnav.task.search

        tmpnav.task.search.route_edits = lambda *_, **__: []  # type: ignore[assignment]
    work = Path(tempfile.mkdtemp(prefix="tmpnav-references-"))
    # robots go through each other (no waits, no detours): the reference has neither
    options = PlanOptions.of(
        costs="table", objective=args.objective, encoding="single", keep_apart=False, cache_dir=work / "cache"
    )
    rows = []
    for rooms in [int(x) for x in args.rooms.split(",")]:
        for seed in range(1, args.seeds + 1):
            path = write(office(rooms, 2, seed), work / f"office-{rooms}-{seed}.yaml")
            t0 = time.perf_counter()
            report = plan(path, options.but(accept_risk=True))
            seconds = time.perf_counter() - t0
            t1 = time.perf_counter()
            table = whole_table(report, options)
            seen = [k for k, v in report.table.single.items() if table.single.get(k) != v]
            assert not seen, f"the whole table disagrees with the plan's on {seen[:3]}"
            best = optimum(table, list(report.scenario.goals.visit), args.objective)
            reference_s = time.perf_counter() - t1
            got = report.planner_cost if args.objective == "cost" else float(report.task.makespan or math.nan)
            gap = (got - best) / best if best > 0 else 0.0
            # a move over the risk threshold is priced at RISK_PENALTY per unit of excess: the cost
            # reference holds it, the makespan's does not (such an instance is left out of its counts)
            risky = report.planner_cost >= RISK_PENALTY * 1e-3
            rows.append({
                "rooms": rooms, "seed": seed, f"tmpnav_{args.objective}": round(got, 6),
                "held_karp_optimum": round(best, 6),
                "gap_percent": round(100 * gap, 4), "status": str(report.task.status), "plan_s": round(seconds, 2),
                "held_karp_s": round(reference_s, 2), "move_over_threshold": risky,
            })  # fmt: skip
            if args.objective == "makespan":
                routed = minmax(table, report.scenario.goals, span_weight_of(report.scenario))
                rows[-1]["ortools_minmax"] = round(routed, 6)
                rows[-1]["gap_to_ortools_percent"] = round(100 * (got - routed) / routed, 4)
            print(rows[-1], flush=True)
    stem = ("references" if args.objective == "cost" else "references-makespan") + (
        "-without-route-edits" if args.without_route_edits else ""
    )
    with (args.output / f"{stem}.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [
        f"tmpnav (costs table, objective {args.objective}, encoding single) against Held-Karp on the same table, "
        f"{len(rows)} instances"
    ]
    left_out = args.objective == "makespan"
    for rooms in sorted({r["rooms"] for r in rows}):
        mine = [
            r for r in rows if r["rooms"] == rooms and not (args.objective == "makespan" and r["move_over_threshold"])
        ]
        gaps = [round(float(r["gap_percent"]), 3) + 0.0 for r in mine]  # + 0.0: no "-0.000" from rounding
        lines.append(
            f"  {rooms} rooms: optimal in {sum(g <= 1e-6 for g in gaps)}/{len(mine)}, gap median "
            f"{statistics.median(gaps):.3f}%, max {max(gaps):.3f}%; plan median "
            f"{statistics.median(float(r['plan_s']) for r in mine):.1f} s"
        )
        if args.objective == "makespan":
            routed = [float(r["gap_to_ortools_percent"]) for r in mine]
            lines.append(
                f"    against OR-Tools' min-max ({MINMAX_SOLUTIONS} solutions): within 5% in "
                f"{sum(g <= 5.0 + 1e-6 for g in routed)}/{len(mine)}, as good or better in "
                f"{sum(g <= 1e-6 for g in routed)}/{len(mine)}, largest {max(routed):+.3f}%"
            )
    risky = [f"{r['rooms']} rooms seed {r['seed']}" for r in rows if r["move_over_threshold"]]
    if risky:
        lines.append(
            "plans with a move over the risk threshold (priced at RISK_PENALTY; "
            + (
                "the makespan's reference has no such price, left out above"
                if args.objective == "makespan"
                else "in both"
            )
            + "): "
            + ", ".join(risky)
        )
    lines += [
        "never below the optimum: "
        + str(all(float(r["gap_percent"]) >= -1e-6 for r in rows if not (left_out and r["move_over_threshold"]))),
        f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}",
        f"command: python benchmarks/bench_references.py --rooms {args.rooms} --seeds {args.seeds} "
        f"--objective {args.objective}{' --without-route-edits' if args.without_route_edits else ''} -o {args.output}",
    ]
    (args.output / f"{stem}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
