"""ENHSP in one JVM for the run (its server process) against a JVM process per solve (issue 21, items 1 and 4).

    python benchmarks/enhsp/bench_enhsp.py -o benchmarks/enhsp [--sessions 3] [--repeat 3]

Three measurements, each with ``TMPNAV_ENHSP=process`` and with the default (the JVM):

- per sub-problem: the sub-problems the anytime search solved in one run of the 10-room
  corridor (``configs/corridor-2robots.yaml``, recorded first), solved again in order by a
  fresh process per mode; the first solve (JVM start included) is reported apart;
- ``tmpnav bench --rooms 10 --sessions N``: the median cold time of the default mode;
- ``tmpnav plan configs/corridor-2robots.yaml`` in a fresh process with an empty cache
  (``--cache-dir`` a new folder), the numba cache warm (one run first): wall time, median.

Writes results.json and summary.md with the machine's load (a shared 2-core machine: compare
the two modes of one run, not runs of different days).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CORRIDOR = ROOT / "configs" / "corridor-2robots.yaml"
MODES = {"process": {"TMPNAV_ENHSP": "process"}, "jvm": {"TMPNAV_ENHSP": "jvm"}}

#: a run of the corridor that writes each sub-problem it solves into RECORD_DIR
RECORD = """
import itertools, os, sys
import tmpnav.task.pddl_text as p, tmpnav.task.solve as s, tmpnav.task.unfolded as u
out, count, solve = sys.argv[1], itertools.count(), s.solve_text
def record(domain, problem, planner, timeout):
    d = os.path.join(out, f"{next(count):03d}")
    os.makedirs(d)
    for name, text in (("domain.pddl", domain), ("problem.pddl", problem), ("planner", planner)):
        open(os.path.join(d, name), "w").write(text)
    return solve(domain, problem, planner, timeout)
p.solve_text = u.solve_text = record
from tmpnav.cli.commands import main
sys.argv = ["tmpnav", "plan", sys.argv[2], "--cache-dir", sys.argv[3], "-q", "--anytime-budget", "60"]
main()
"""

#: solve the recorded sub-problems in order; print the seconds of each, as JSON
SOLVE = """
import json, pathlib, sys, time
from tmpnav.task.solve import engine_class, solve_text
times = []
for d in sorted(pathlib.Path(sys.argv[1]).iterdir()):
    text = [(d / n).read_text() for n in ("domain.pddl", "problem.pddl", "planner")]
    engine_class(text[2])  # unified-planning imported before the clock starts
    start = time.perf_counter()
    solve_text(text[0], text[1], text[2], 60.0)
    times.append(time.perf_counter() - start)
print(json.dumps(times))
"""


def run(args: list[str], env: dict[str, str]) -> tuple[float, subprocess.CompletedProcess[str]]:
    start = time.perf_counter()
    proc = subprocess.run(args, env={**os.environ, **env}, capture_output=True, text=True, cwd=ROOT)
    return time.perf_counter() - start, proc


def per_subproblem(tmp: Path) -> dict[str, object]:
    subs = tmp / "subs"
    subs.mkdir()
    _, proc = run([sys.executable, "-c", RECORD, str(subs), str(CORRIDOR), str(tmp / "record-cache")], {})
    assert proc.returncode == 0, proc.stderr
    result: dict[str, object] = {"subproblems": len(list(subs.iterdir()))}
    for mode, env in MODES.items():
        _, proc = run([sys.executable, "-c", SOLVE, str(subs)], env)
        assert proc.returncode == 0, proc.stderr
        times = json.loads(proc.stdout.strip().splitlines()[-1])
        result[mode] = {
            "first_ms": round(times[0] * 1000),
            "median_ms": round(statistics.median(times[1:]) * 1000),
            "total_s": round(sum(times), 2),
        }
    return result


def bench(tmp: Path, sessions: int) -> dict[str, object]:
    result: dict[str, object] = {}
    for mode, env in MODES.items():
        out = tmp / f"bench-{mode}"
        args = [sys.executable, "-m", "tmpnav", "bench", "--rooms", "10", "--sessions", str(sessions), "-o", str(out)]
        wall, proc = run(args, env)
        assert proc.returncode == 0, proc.stderr
        with open(out / "bench.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        phases = {}
        for phase in ("cold", "warm", "replan"):
            mine = [r for r in rows if r["phase"] == phase]
            phases[phase] = {
                key: round(statistics.median(float(r[key] or 0) for r in mine), 2)
                for key in ("total_s", "planner_s", "oracle_s")
            }
        result[mode] = {"wall_s": round(wall, 1), "medians": phases, "stopped": sorted({r["stopped"] for r in rows})}
    return result


def fresh_plan(tmp: Path, repeat: int) -> dict[str, object]:
    run([sys.executable, "-m", "tmpnav", "plan", str(CORRIDOR), "-q", "--cache-dir", str(tmp / "numba-warm")], {})
    result: dict[str, object] = {}
    for mode, env in MODES.items():
        walls = []
        for i in range(repeat):
            wall, proc = run(
                [sys.executable, "-m", "tmpnav", "plan", str(CORRIDOR), "-q", "--cache-dir", str(tmp / f"{mode}-{i}")],
                env,
            )
            assert proc.returncode == 0, proc.stderr
            walls.append(wall)
        result[mode] = {"median_s": round(statistics.median(walls), 2), "runs_s": [round(w, 2) for w in walls]}
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=Path(__file__).parent)
    parser.add_argument("--sessions", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--only", choices=("subproblems", "bench", "plan"), action="append")
    ns = parser.parse_args()
    only = ns.only or ["subproblems", "bench", "plan"]
    results: dict[str, object] = {"machine": {"cores": os.cpu_count(), "load_before": os.getloadavg()}}
    with tempfile.TemporaryDirectory(prefix="tmpnav-bench-enhsp-") as name:
        tmp = Path(name)
        if "subproblems" in only:
            results["subproblems"] = per_subproblem(tmp)
        if "plan" in only:
            results["fresh_plan"] = fresh_plan(tmp, ns.repeat)
        if "bench" in only:
            results["bench"] = bench(tmp, ns.sessions)
    results["machine"]["load_after"] = os.getloadavg()  # type: ignore[index]
    ns.output.mkdir(parents=True, exist_ok=True)
    (ns.output / "results.json").write_text(json.dumps(results, indent=1) + "\n")
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
