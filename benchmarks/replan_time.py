"""Where a warm `tmpnav replan` command spends its time (issue 56: at most 5 s as a command).

    python benchmarks/replan_time.py SCENARIO STATE [--runs 3] [-o benchmarks/replan_time]

Plans SCENARIO once (the cache warm), replans it from STATE once (the moves from the new starts
cached), then times `tmpnav replan SCENARIO --plan plan.json --state STATE -o DIR --export nav2`
``--runs`` more times as a command (the wall time of the process), and the same replan's phases
in one process, as the command runs them:

- imports: ``import tmpnav.cli`` and what the replan imports (OR-Tools, OMPL, matplotlib, ...);
- load: the scenario and its world (the map, its rooms, doors, landmarks);
- base roadmap: the first plan's roadmap read from the cache (the revision adds the starts);
- plan: ``pipeline.plan`` of the revision, by its own stage times (roadmap with the starts,
  oracle, planner: the search with ENHSP's JVM, bound, resimulate);
- write: plan.json, plan.png, schedule.png, the PDDL and the nav2 files.

Prints a table and writes ``<scenario>.txt`` into -o.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def command(*args: str | Path) -> tuple[float, subprocess.CompletedProcess[str], float]:
    """Run ``python -m tmpnav ARGS``; its wall time, its result and the CPU time it and its
    children (ENHSP's JVM) took: on a shared machine the wall time waits for the others."""
    cpu = _children_cpu()
    began = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=1800
    )
    return time.perf_counter() - began, proc, _children_cpu() - cpu


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


#: the phases of a replan in one process, run in a fresh interpreter (cold imports, as a command)
PHASES = r"""
import json, sys, time
from pathlib import Path
t = {}
began = time.perf_counter()
import tmpnav.cli  # noqa: F401  the command's own imports
from tmpnav import pipeline
from tmpnav.cli.options import plan_options  # noqa: F401
from tmpnav.replan import _grown, nav2_files, read_plan, read_state
from tmpnav.replan import replan as run
from tmpnav.report.outputs import write_outputs
import ortools.constraint_solver.pywrapcp, ompl.base, matplotlib.pyplot  # noqa: E401, F401
t["imports"] = time.perf_counter() - began
scenario, plan, state, cache, out = sys.argv[1:6]
options = pipeline.PlanOptions.of(cache_dir=Path(cache))
began = time.perf_counter()
loaded = pipeline.load_world(scenario, options.overrides)
t["load"] = time.perf_counter() - began
began = time.perf_counter()
_grown(*loaded, options)
t["base roadmap"] = time.perf_counter() - began
began = time.perf_counter()
report = run(scenario, plan, state, options, loaded=loaded)
t["plan"] = time.perf_counter() - began
began = time.perf_counter()
nav2 = {f"nav2/{name}": text for name, text in nav2_files(report).items()}
write_outputs(report, Path(out), pipeline.pddl_texts(report), nav2)
t["write"] = time.perf_counter() - began
stages = {k: round(v, 3) for k, v in report.times.seconds.items()}
print(json.dumps({"phases": t, "stages": stages, "search": report.task.search.seconds if report.task.search else None}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", type=Path)
    parser.add_argument("state", type=Path)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("-o", "--output", type=Path, default=None)
    parser.add_argument("--cache-dir", type=Path, default=None, help="a cache to reuse (default: a new one)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        cache = args.cache_dir or tmp / "cache"
        wall, proc, _ = command("plan", args.scenario, "-q", "--cache-dir", cache, "-o", tmp / "first")
        if proc.returncode != 0:
            sys.exit(proc.stderr)
        print(f"first plan: {wall:.1f} s")
        plan = tmp / "first" / "plan.json"
        replan = ("replan", args.scenario, "--plan", plan, "--state", args.state, "--cache-dir", cache)
        wall, proc, _ = command(*replan, "-o", tmp / "warm-up", "--export", "nav2")
        print(f"first replan (the moves from the new starts computed): {wall:.1f} s, exit {proc.returncode}")
        walls, cpus = [], []
        for k in range(args.runs):
            wall, proc, cpu = command(*replan, "-o", tmp / f"run{k}", "--export", "nav2")
            walls.append(wall)
            cpus.append(cpu)
        phases = []
        for k in range(args.runs):
            out = tmp / f"phases{k}"
            cpu = _children_cpu()
            done = subprocess.run(
                [sys.executable, "-c", PHASES, str(args.scenario), str(plan), str(args.state), str(cache), str(out)],
                capture_output=True,
                text=True,
                cwd=ROOT,
                timeout=1800,
            )
            if done.returncode != 0:
                sys.exit(done.stderr)
            phases.append(json.loads(done.stdout.strip().splitlines()[-1]) | {"cpu": _children_cpu() - cpu})
    lines = [f"{args.scenario} from {args.state}: {args.runs} warm runs (median)"]
    lines.append(
        f"  command wall time: {statistics.median(walls):.2f} s  (runs: {', '.join(f'{w:.2f}' for w in walls)})"
    )
    lines.append(f"  command CPU time:  {statistics.median(cpus):.2f} s  (its process and ENHSP's JVM)")
    for name in phases[0]["phases"]:
        lines.append(f"  {name:<13} {statistics.median(p['phases'][name] for p in phases):6.2f} s")
    for name in phases[0]["stages"]:
        lines.append(f"    {name:<11} {statistics.median(p['stages'].get(name, 0.0) for p in phases):6.2f} s")
    lines.append(f"    search      {statistics.median(p['search'] or 0.0 for p in phases):6.2f} s (its own clock)")
    lines.append(f"  phases' CPU time: {statistics.median(p['cpu'] for p in phases):.2f} s")
    text = "\n".join(lines)
    print(text)
    if args.output is not None:
        args.output.mkdir(parents=True, exist_ok=True)
        (args.output / f"{args.scenario.stem}.txt").write_text(text + "\n")


if __name__ == "__main__":
    main()
