"""Plans that use the whole fleet: rooms per robot, makespan, bound and gap on generated offices.

    .venv/bin/python benchmarks/bench_fleet.py [--sizes office:60:16:1,office:100:16:1] [--seeds 1]
        [--objectives weighted,makespan] [--reference 10]

For each generated building (benchmarks/families.py: kind, rooms, robots, seed) and objective, a
fresh ``tmpnav plan`` with default options otherwise, its CPU time (user + sys of the command
and its children) and the machine's load (1-minute average, before and after); with
``--reference K`` also a run with ``--objective makespan`` and K times the default work
budget, the yardstick of the makespan. The oracle's cache is the default one: run once to
fill it, then again to measure the search rather than the oracle. Appends one row per run to
benchmarks/fleet/fleet.txt: the run, its objective's value, makespan, lower bound, gap, how
the search stopped, the sub-problems it solved, CPU seconds, wall seconds, load, and the rooms
each robot visits.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from families import KINDS, write  # noqa: E402

OUT = ROOT / "benchmarks" / "fleet"
COLUMNS = (
    "kind,rooms,robots,seed,objective,work,value,makespan,bound,gap,stopped,subproblems,"
    "cpu_s,wall_s,load,rooms_per_robot"
)


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def plan(scenario: Path, folder: Path, args: list[str]) -> tuple[dict[str, object], float, float, str]:
    """plan.json of one ``tmpnav plan`` run, its CPU and wall seconds, the load before/after."""
    load0, cpu0, wall0 = os.getloadavg()[0], children_cpu(), time.perf_counter()
    command = [sys.executable, "-m", "tmpnav", "plan", str(scenario), "-o", str(folder), *args]
    subprocess.run(command, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    cpu, wall = children_cpu() - cpu0, time.perf_counter() - wall0
    doc = json.loads((folder / "plan.json").read_text())
    return doc, cpu, wall, f"{load0:.1f}/{os.getloadavg()[0]:.1f}"


def row(name: str, objective: str, work: str, doc: dict, cpu: float, wall: float, load: str) -> str:  # type: ignore[type-arg]
    schedule, bound, search = doc["schedule"], doc["bound"], doc["search"]
    rooms = "/".join(str(r["rooms"]) for r in schedule["robots"].values())
    gap = bound.get("gap")
    return (
        f"{name},{objective},{work},{doc['objective']['planner']:.3f},{schedule['makespan']:.1f},"
        f"{bound['value']:.3f},{'' if gap is None else f'{gap:.3f}'},{search['stopped']},{search['subproblems']},"
        f"{cpu:.1f},{wall:.1f},{load},{rooms}"
    )


def building(kind: str, rooms: int, robots: int, seed: int, objectives: list[str], reference: int, tmp: Path) -> None:
    name = f"{kind},{rooms},{robots},{seed}"
    scenario = write(KINDS[kind](rooms, robots, seed), tmp / f"{kind}-{rooms}-{robots}-{seed}.yaml")
    work = None
    for objective in objectives:
        args = [] if objective == "default" else ["--objective", objective]
        doc, cpu, wall, load = plan(scenario, tmp / objective, args)
        work = doc["search"]["work_budget"]
        emit(row(name, doc["objective"]["name"], "default", doc, cpu, wall, load))
    if reference and work:
        args = ["--objective", "makespan", "--anytime-work", str(reference * int(work))]
        doc, cpu, wall, load = plan(scenario, tmp / "reference", args)
        emit(row(name, "makespan", f"{reference}x", doc, cpu, wall, load))


def emit(line: str) -> None:
    print(line, flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    with (OUT / "fleet.txt").open("a") as out:
        out.write(line + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="office:60:16:1", help="kind:rooms:robots:first_seed,...")
    parser.add_argument("--seeds", type=int, default=1, help="seeds per size, from its first")
    parser.add_argument("--objectives", default="default,makespan", help="default (the scenario's) or a name, ...")
    parser.add_argument("--reference", type=int, default=0, help="also --objective makespan at K x the work budget")
    args = parser.parse_args()
    stamp = f"# {' '.join(sys.argv[1:]) or 'defaults'}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    emit(stamp)
    emit(COLUMNS)
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes.split(","):
            kind, rooms, robots, first = size.split(":")
            for seed in range(int(first), int(first) + args.seeds):
                building(kind, int(rooms), int(robots), seed, args.objectives.split(","), args.reference, Path(tmp))


if __name__ == "__main__":
    main()
