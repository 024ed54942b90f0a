"""Stations at scale: a generated rack hall with 40 stations in 10 places and 4 robots, planned
with its defaults.

    .venv/bin/python benchmarks/bench_stations.py [--seeds 1,2,3] [--stations 40] [--places 10] [--robots 4]

For every seed, the hall of benchmarks/families.py (``warehouse --stations``) is written and
planned by one fresh ``tmpnav plan ... --export nav2`` with a cold cache of its own: the
command's wall time, its CPU time (user + sys of the command and every process it started:
oracle workers, the planner's JVM), tmpnav's own stage times, the load average before it (the
machine is shared), the objective and makespan, and whether the nav2 files hold one goal per
station, at its pose. Writes runs.csv into benchmarks/stations/ (or ``-o DIR``); the figures
are in benchmarks/README.md, "Stations".
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from families import warehouse, write  # benchmarks/ is the script's folder, first on sys.path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "stations"
TMPNAV = [sys.executable, "-m", "tmpnav"]
STAGES = ("roadmap", "oracle", "encode", "planner", "bound", "resimulate", "other", "total")


def _cpu() -> float:
    """User + sys seconds of the children waited for so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _goals_per_station(nav2: Path, poses: dict[str, list[Any]]) -> bool:
    """Whether the robots' waypoint files hold one goal per station, each at its pose."""
    goals: list[dict[str, str]] = []
    for path in sorted(nav2.glob("*.csv")):
        lines = [x for x in path.read_text().splitlines() if not x.startswith("#")]
        goals += [row for row in csv.DictReader(lines) if row["kind"] == "goal"]
    if sorted(row["room"] for row in goals) != sorted(poses):
        return False
    return all(
        abs(float(row["x"]) - poses[row["room"]][0]) < 1e-6 and abs(float(row["y"]) - poses[row["room"]][1]) < 1e-6
        for row in goals
    )


def run(seed: int, stations: int, places: int, robots: int, work: Path) -> dict[str, Any]:
    """One cold plan of the seeded hall; its figures as a row."""
    doc = warehouse(places, robots, seed, stations=stations)
    scenario = write(doc, work / f"hall-{seed}.yaml")
    poses = {j["name"]: j["pose"] for j in doc["goals"]["jobs"]}
    out = work / f"out-{seed}"
    load = os.getloadavg()[0]
    cpu, wall = _cpu(), time.perf_counter()
    cache = ("--cache-dir", str(work / f"cache-{seed}"))
    proc = subprocess.run(
        [*TMPNAV, "plan", str(scenario), "-q", *cache, "-o", str(out), "--export", "nav2"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    wall, cpu = time.perf_counter() - wall, _cpu() - cpu
    row: dict[str, Any] = {"seed": seed, "stations": len(poses), "exit": proc.returncode, "load": round(load, 2)}
    row |= {"wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}
    if proc.returncode != 0:
        print(proc.stderr, file=sys.stderr)
        return row
    plan = json.loads((out / "plan.json").read_text())
    row |= {f"{k}_s": round(plan["timings"][k], 2) for k in STAGES}
    row |= {
        "objective": round(plan["objective"]["resimulated"], 3),
        "makespan_s": plan["schedule"]["makespan"],
        "nav2_goal_per_station": _goals_per_station(out / "nav2", poses),
    }
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--stations", type=int, default=40)
    parser.add_argument("--places", type=int, default=10)
    parser.add_argument("--robots", type=int, default=4)
    parser.add_argument("-o", "--output", type=Path, default=OUT)
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory(prefix="tmpnav-stations-") as tmp:
        for seed in (int(s) for s in args.seeds.split(",")):
            row = run(seed, args.stations, args.places, args.robots, Path(tmp))
            print(row, flush=True)
            rows.append(row)
    fields = list(dict.fromkeys(k for row in rows for k in row))
    with open(args.output / "runs.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.output / 'runs.csv'}")


if __name__ == "__main__":
    main()
