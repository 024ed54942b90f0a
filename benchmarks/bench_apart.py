"""Robots kept apart inside the search: the plan it picks is the plan executed.

    .venv/bin/python benchmarks/bench_apart.py [--sizes warehouse:12:4,office:12:4] [--seeds 8] [--no-lidar]

For every generated building (benchmarks/families.py) and seed, the default plan twice, in one
process, a cold cache each: as ``tmpnav plan`` makes it (every plan the anytime search
would take priced as executed, robots kept apart: tmpnav.attachment.apart.ExecutedCost) and
with the search judging plans as planned and the robots kept apart afterwards (what tmpnav did
before). For each: the objective the search reported for its plan, the objective executed
(re-simulated with its waits, detours and sidesteps), the conflicts as planned and left, the
longest wait, the seconds of planning. Writes benchmarks/apart/runs.csv and summary.md.
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from families import KINDS, write  # benchmarks/ is the script's folder, first on sys.path

import tmpnav.planning.anytime as anytime
from tmpnav.errors import TmpnavError
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.task.objectives import OBJECTIVES

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "apart"


def measure(path: Path, cache: Path, inside: bool) -> dict[str, object]:
    priced = anytime._executed
    if not inside:
        anytime._executed = lambda run: None  # the search judges plans as planned
    start = time.perf_counter()
    try:
        report = plan(path, PlanOptions().but(cache_dir=cache, accept_risk=True, replan=True))
    except TmpnavError as err:
        return {"error": str(err).splitlines()[0]}
    finally:
        anytime._executed = priced
    seconds = time.perf_counter() - start
    s = report.scenario
    executed = OBJECTIVES[s.planner.objective].value(report.resimulated_cost, report.schedule.makespan, s.cost)
    search = report.task.search
    searched = search.history[-1][1] if search is not None and search.history else float("nan")
    apart = report.apart
    waits = [w for _, w in apart.waits] if apart is not None else []
    return {
        "searched": round(searched, 3),
        "executed": round(executed, 3),
        "conflicts_planned": apart.conflicts_before if apart is not None else 0,
        "conflicts_left": apart.conflicts_left if apart is not None else 0,
        "longest_wait": max(waits, default=0.0),
        "makespan": report.schedule.makespan,
        "seconds": round(seconds, 2),
        "error": "",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="warehouse:12:4,office:12:4")
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument(
        "--no-lidar", action="store_true", help="robots without the range sensor: landmarks only, no threshold"
    )
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes.split(","):
            kind, rooms, robots = size.split(":")
            for seed in range(args.seeds):
                name = f"{kind}-{rooms}-{robots}-{seed}"
                doc = KINDS[kind](int(rooms), int(robots), seed, lidar=not args.no_lidar)
                path = write(doc, Path(tmp) / f"{name}.yaml")
                for inside in (True, False):  # a cold cache each
                    row = {"instance": name, "search": "priced" if inside else "repaired after"}
                    row.update(measure(path, Path(tmp) / f"cache-{name}-{inside}", inside))
                    rows.append(row)
                    print(row, flush=True)
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(OUT / "runs.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        f"# `python benchmarks/bench_apart.py --sizes {args.sizes} --seeds {args.seeds}"
        f"{' --no-lidar' if args.no_lidar else ''}`, "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        "",
        "| instance | conflicts as planned | search | objective searched | executed | executed vs searched "
        "| longest wait [s] | conflicts left | seconds |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    ratios: dict[str, list[float]] = {"priced": [], "repaired after": []}
    gains = []
    for i in range(0, len(rows), 2):
        pair = rows[i : i + 2]
        if any(r["error"] for r in pair):
            lines.append(f"| {pair[0]['instance']} | error: {pair[0]['error'] or pair[1]['error']} |||||||")
            continue
        for r in pair:
            rise = 100.0 * (float(r["executed"]) / float(r["searched"]) - 1.0)  # type: ignore[arg-type]
            ratios[str(r["search"])].append(rise)
            lines.append(
                f"| {r['instance']} | {r['conflicts_planned']} | {r['search']} | {r['searched']} | {r['executed']} "
                f"| {rise:+.1f}% | {r['longest_wait']} | {r['conflicts_left']} | {r['seconds']} |"
            )
        gains.append(100.0 * (float(pair[0]["executed"]) / float(pair[1]["executed"]) - 1.0))  # type: ignore[arg-type]
    lines += [""]
    for name, values in ratios.items():
        if values:
            lines.append(
                f"- {name}: executed objective against the one searched, largest {max(values):+.2f}%, "
                f"median {float(np.median(values)):+.2f}%"
            )
    if gains:
        lines.append(
            f"- executed objective priced against repaired after: median {float(np.median(gains)):+.2f}%, "
            f"best {min(gains):+.2f}%, worst {max(gains):+.2f}% ({len(gains)} instances)"
        )
    (OUT / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
