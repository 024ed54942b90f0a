"""Safe by default: the chance constraint in force, plans free of conflicts, checked by execution.

    .venv/bin/python benchmarks/bench_safety.py plans          # the shipped teams with their defaults
    .venv/bin/python benchmarks/bench_safety.py default        # default against --max-risk none, side by side
    .venv/bin/python benchmarks/bench_safety.py simulate [--sessions 1000]   # building-4robots executed
    .venv/bin/python benchmarks/bench_safety.py paths          # what the clearance and the threshold cost

Each writes benchmarks/safety/<what>.txt and prints it.

* plans: ``tmpnav plan`` of every shipped scenario with 2 or more robots and a range sensor, and of
  a ``tmpnav rooms`` skeleton of the warehouse map with a third robot, with their default options:
  the threshold in force, the largest move bound, the independent checker's conflicts (exit code
  10 when some are left), the waits the plan holds (kept apart) against its makespan, the time.
* default: fresh commands with the default threshold and with ``--max-risk none`` (the lidar kept):
  time and objective of each, alternating which goes first (building-20, building-4robots, 40 rooms
  with 4 robots).
* simulate: ``tmpnav simulate configs/building-4robots.yaml --sessions N -o DIR``: wall hits and
  robot contacts with their 95% intervals, per robot and per move against the move's bound.
* paths: building-20 and building-4robots planned three ways, a cold cache each: the defaults
  (max_risk 0.05, paths 0.5 m clear of walls), ``--max-risk none`` (the same paths), and
  ``--max-risk none --clearance 0`` (the shortest paths): objective, makespan, rooms per robot.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from bench_lidar import forty_rooms  # benchmarks/ is the script's folder, first on sys.path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "safety"
TMPNAV = [sys.executable, "-m", "tmpnav"]
SHIPPED = (
    "building-20",
    "building-2robots",
    "building-4robots",
    "building-8robots",
    "warehouse-2robots",
    "warehouse-4robots",
    "warehouse-8robots",
    "office-ros",
    "office-rooms",
)


def _tmpnav(*args: str) -> tuple[subprocess.CompletedProcess[str], float]:
    start = time.perf_counter()
    proc = subprocess.run([*TMPNAV, *args], cwd=ROOT, capture_output=True, text=True)
    return proc, time.perf_counter() - start


def _warehouse_skeleton(folder: Path) -> Path:
    """`tmpnav rooms` of the warehouse's ROS map, with a third robot where the second stands, 4 m on."""
    target = folder / "warehouse-rooms.yaml"
    proc, _ = _tmpnav("rooms", str(ROOT / "configs" / "warehouse" / "map.yaml"), "-o", str(target))
    if proc.returncode != 0:
        sys.exit(f"tmpnav rooms failed: {proc.stderr[-800:]}")
    doc = yaml.safe_load(target.read_text())
    doc["map"]["ros"] = str(ROOT / "configs" / "warehouse" / "map.yaml")
    second = doc["robots"][-1]
    x, y, theta = second["pose"]
    for dx, dy in ((4.0, 0.0), (-4.0, 0.0), (0.0, 4.0), (0.0, -4.0)):
        doc["robots"].append({"name": "r3", "pose": [x + dx, y + dy, theta], "radius": second.get("radius", 0.25)})
        target.write_text(yaml.safe_dump(doc, sort_keys=False))
        if _tmpnav("validate", str(target))[0].returncode == 0:
            return target
        doc["robots"].pop()
    sys.exit("no place for a third robot next to the skeleton's second")


def plans() -> str:
    lines = ["`tmpnav plan SCENARIO -o DIR` with default options, a cold cache each"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = {name: ROOT / "configs" / f"{name}.yaml" for name in SHIPPED}
        cases["warehouse map, tmpnav rooms, 3 robots"] = _warehouse_skeleton(folder)
        for name, scenario in cases.items():
            out = folder / name.replace(" ", "_").replace(",", "")
            proc, seconds = _tmpnav("plan", str(scenario), "-q", "--cache-dir", str(folder / "cache"), "-o", str(out))
            if proc.returncode != 0:
                first = proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "?"
                lines.append(f"{name}: exit {proc.returncode} after {seconds:.1f} s: {first}")
                print(lines[-1], flush=True)
                continue
            doc = json.loads((out / "plan.json").read_text())
            risks = [m["risk"] for a in doc["actions"] for m in a["moves"]]
            makespan = doc["schedule"]["makespan"]
            per_robot = doc["schedule"]["robots"]
            waits = max((r["waits"] for r in per_robot.values()), default=0.0)
            constraint = re.search(r"chance constraint: (.*)", proc.stdout)
            conflicts = re.search(r"robots in each other's way: ([^,\n]*)", proc.stdout)
            lines.append(
                f"{name}: {seconds:.1f} s; {constraint.group(1) if constraint else '?'}; largest move bound "
                f"{max(risks, default=0.0):.2g}; conflicts {conflicts.group(1) if conflicts else '?'}; "
                f"makespan {makespan:.1f} s, the most a robot waits {waits:.1f} s ({100 * waits / makespan:.1f}% of "
                "the makespan)"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


def default(runs: int) -> str:
    lines = ["fresh `tmpnav plan` commands, a cold cache each: the default threshold (0.05) against --max-risk none"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = {
            "building-20": ROOT / "configs" / "building-20.yaml",
            "building-4robots": ROOT / "configs" / "building-4robots.yaml",
            "40 rooms / 4 robots": forty_rooms(folder),
        }
        for name, scenario in cases.items():
            seconds: dict[bool, list[float]] = {True: [], False: []}
            objective: dict[bool, str] = {}
            for k in range(runs):
                for constrained in (True, False) if k % 2 == 0 else (False, True):
                    cache = folder / f"c-{len(list(folder.iterdir()))}"
                    extra = [] if constrained else ["--max-risk", "none"]
                    proc, s = _tmpnav("plan", str(scenario), "-q", "--cache-dir", str(cache), *extra)
                    if proc.returncode != 0:
                        sys.exit(f"{name} failed ({proc.returncode}): {proc.stderr[-600:]}")
                    seconds[constrained].append(s)
                    found = re.search(r"objective .*?: ([0-9.]+)", proc.stdout)
                    objective[constrained] = found.group(1) if found else "?"
            ratio = np.median(seconds[True]) / np.median(seconds[False])
            rise = float(objective[True]) / float(objective[False]) - 1.0
            lines.append(
                f"{name}: default {', '.join(f'{s:.1f}' for s in seconds[True])} s, objective {objective[True]}; "
                f"--max-risk none {', '.join(f'{s:.1f}' for s in seconds[False])} s, objective {objective[False]}; "
                f"time ratio {ratio:.2f}, objective {100 * rise:+.1f}%"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


def paths() -> str:
    lines = ["fresh `tmpnav plan` commands, a cold cache each: what keeping clear of walls and the threshold cost"]
    variants = {
        "default": [],
        "--max-risk none": ["--max-risk", "none"],
        "shortest paths": ["--max-risk", "none", "--clearance", "0"],
    }
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("building-20", "building-4robots"):
            for label, extra in variants.items():
                out = Path(tmp) / f"{name}-{len(list(Path(tmp).iterdir()))}"
                proc, seconds = _tmpnav(
                    "plan", f"configs/{name}.yaml", "-q", *extra, "--cache-dir", str(out / "c"), "-o", str(out)
                )
                if proc.returncode != 0:
                    sys.exit(f"{name} {label} failed ({proc.returncode}): {proc.stderr[-600:]}")
                doc = json.loads((out / "plan.json").read_text())
                rooms = {r: v["rooms"] for r, v in doc["schedule"]["robots"].items()}
                risks = [m["risk"] for a in doc["actions"] for m in a["moves"]]
                found = re.search(r"objective .*?: ([0-9.]+)", proc.stdout)
                lines.append(
                    f"{name}, {label}: objective {found.group(1) if found else '?'}, makespan "
                    f"{doc['schedule']['makespan']:.1f} s, rooms per robot {rooms}, largest move bound "
                    f"{max(risks, default=0.0):.2g}, {seconds:.1f} s"
                )
                print(lines[-1], flush=True)
    return "\n".join(lines)


def simulate(sessions: int) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "sim"
        args = ["simulate", "configs/building-4robots.yaml", "--sessions", str(sessions), "-q"]
        proc, seconds = _tmpnav(*args, "--cache-dir", str(Path(tmp) / "cache"), "-o", str(out))
        if proc.returncode != 0:
            sys.exit(f"simulate failed ({proc.returncode}): {proc.stderr[-800:]}")
        moves = (out / "moves.csv").read_text()
    return f"$ tmpnav {' '.join(args)} -o DIR ({seconds:.0f} s)\n{proc.stdout.strip()}\n\nmoves.csv:\n{moves}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("plans", "default", "simulate", "paths"))
    parser.add_argument("--runs", type=int, default=2, help="default: runs of each case, each way")
    parser.add_argument("--sessions", type=int, default=1000, help="simulate: executions")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    runs = {
        "plans": plans,
        "default": lambda: default(args.runs),
        "simulate": lambda: simulate(args.sessions),
        "paths": paths,
    }
    text = runs[args.what]()
    stamp = f"# {' '.join(sys.argv[1:])}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n"
    (OUT / f"{args.what}.txt").write_text(stamp + text + "\n")
    print(text)


if __name__ == "__main__":
    main()
