"""The paper's model on generated buildings: landmark-only offices, fresh ``tmpnav plan`` commands.

    .venv/bin/python benchmarks/bench_landmark_family.py [--seeds 1-5] [--rooms 24] [--goals 20]
        [--robots 2] [--code DIR] [--label NAME] [-o DIR]

For each seed, benchmarks/families.py's office of ``--rooms`` rooms and ``--robots`` robots without
the lidar (``--no-lidar``: landmarks and partners only, the paper's sensor model), whose goals are
the first ``--goals`` rooms of its ``goals.visit``, planned by one fresh ``tmpnav plan FILE
--cache-dir EMPTY -o OUT`` (a cold cache each, the figures and PDDL files written). Recorded per
run: wall seconds with the 1-minute load average at its start and end, CPU seconds (user + sys of
the command and of every process it started: its oracle workers and ENHSP's JVM), the exit code,
whether the anytime search converged or stopped at a budget, the objective, the search's
sub-problems, and the stage times of plan.json. Writes runs.csv and summary.md into
benchmarks/landmark_family/ (or ``-o DIR``).

``--code DIR`` runs the tmpnav of another checkout (a ``git worktree`` of an older commit): the
command runs as ``python -m tmpnav`` from DIR, whose own ``tmpnav`` package comes first on
``sys.path``. Its bytecode should be compiled first (``python -m compileall -qq tmpnav`` there).
"""

from __future__ import annotations

import argparse
import csv
import ctypes
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from families import office, write  # benchmarks/ is the script's folder, first on sys.path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "landmark_family"
STAGES = ("load", "roadmap", "oracle", "encode", "planner", "bound", "resimulate", "other", "total")
#: prctl(2): orphaned descendants (ENHSP's JVM, if tmpnav did not reap it) are reparented here
PR_SET_CHILD_SUBREAPER = 36


def scenario(rooms: int, robots: int, seed: int, goals: int, folder: Path) -> Path:
    """The landmark-only office of ``seed`` with the first ``goals`` rooms of its goals."""
    doc: dict[str, Any] = office(rooms, robots, seed, lidar=False)
    doc["goals"]["visit"] = doc["goals"]["visit"][:goals]
    return write(doc, folder / f"office-{rooms}-{robots}-seed{seed}-{goals}goals.yaml")


def _cpu(usage: resource.struct_rusage) -> float:
    return usage.ru_utime + usage.ru_stime


def run(path: Path, code: Path, work: Path) -> dict[str, Any]:
    """One fresh command; wall and CPU seconds, the load, what its plan.json says."""
    out, cache = work / "out", work / "cache"
    cache.mkdir()
    before = _cpu(resource.getrusage(resource.RUSAGE_CHILDREN))
    load0 = os.getloadavg()[0]
    start = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "tmpnav", "plan", str(path), "--cache-dir", str(cache), "-o", str(out), "-q"],
        cwd=code,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    _, err = proc.communicate()
    wall = time.perf_counter() - start
    while True:  # descendants left behind, if any, counted too
        try:
            os.wait()
        except ChildProcessError:
            break
    row: dict[str, Any] = {
        "exit": proc.returncode,
        "wall_s": round(wall, 2),
        "cpu_s": round(_cpu(resource.getrusage(resource.RUSAGE_CHILDREN)) - before, 2),
        "load_start": round(load0, 2),
        "load_end": round(os.getloadavg()[0], 2),
    }
    if proc.returncode != 0 or not (out / "plan.json").exists():
        return {**row, "error": (err.strip().splitlines() or [""])[-1]}
    doc = json.loads((out / "plan.json").read_text())
    search = doc.get("search") or {}
    objective = doc["objective"]["planner"] if isinstance(doc.get("objective"), dict) else doc["cost"]["planner"]
    row.update(
        stopped=search.get("stopped", "exact"),
        objective=round(float(objective), 3),
        subproblems=search.get("subproblems", ""),
        improvements=search.get("improvements", ""),
        roadmap_nodes=doc["roadmap"]["nodes"],
    )
    row.update({f"{k}_s": round(float(doc["timings"].get(k, 0.0)), 2) for k in STAGES})
    return row


def _seeds(text: str) -> list[int]:
    first, _, last = text.partition("-")
    return list(range(int(first), int(last or first) + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="1-5", help="seeds, FIRST-LAST (default: %(default)s)")
    parser.add_argument("--rooms", type=int, default=24)
    parser.add_argument("--goals", type=int, default=20, help="the first GOALS rooms of goals.visit")
    parser.add_argument("--robots", type=int, default=2)
    parser.add_argument("--code", type=Path, default=ROOT, help="the checkout whose tmpnav runs (default: this one)")
    parser.add_argument("--label", default="", help="a name for the code, in the files' names (runs-LABEL.csv)")
    parser.add_argument("-o", "--output", type=Path, default=OUT, help="folder of the results (default: %(default)s)")
    args = parser.parse_args()
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0)
    out = args.output
    out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    with tempfile.TemporaryDirectory() as tmp:
        for seed in _seeds(args.seeds):
            work = Path(tmp) / f"seed{seed}"
            work.mkdir()
            path = scenario(args.rooms, args.robots, seed, args.goals, work)
            rows.append({"seed": seed, **run(path, args.code.resolve(), work)})
            print(rows[-1], flush=True)
    suffix = f"-{args.label}" if args.label else ""
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(out / f"runs{suffix}.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    lines = _summary(rows, args, started)
    (out / f"summary{suffix}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def _summary(rows: list[dict[str, Any]], args: argparse.Namespace, started: str) -> list[str]:
    ok = [r for r in rows if r["exit"] == 0 and "objective" in r]
    converged = sum(r.get("stopped") == "converged" for r in ok)
    head = (
        f"# `python benchmarks/bench_landmark_family.py --seeds {args.seeds} --rooms {args.rooms} --goals "
        f"{args.goals} --robots {args.robots}`{' (' + args.label + ')' if args.label else ''}, {started}, "
        f"{os.cpu_count()} cores, code {args.code}"
    )
    lines = [
        head,
        "",
        "| seed | wall [s] | CPU [s] | load (start, end) | stopped | sub-problems | objective | roadmap | oracle | "
        "planner | bound | other stages | pipeline total |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r not in ok:
            lines.append(f"| {r['seed']} | {r['wall_s']} | {r['cpu_s']} | | exit {r['exit']}: {r.get('error', '')} |")
            continue
        rest = sum(r[f"{k}_s"] for k in ("load", "encode", "resimulate", "other"))
        lines.append(
            f"| {r['seed']} | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['load_start']:.1f}, {r['load_end']:.1f} | "
            f"{r['stopped']} | {r['subproblems']} | {r['objective']:.3f} | {r['roadmap_s']:.2f} | "
            f"{r['oracle_s']:.2f} | {r['planner_s']:.2f} | {r['bound_s']:.2f} | {rest:.2f} | {r['total_s']:.2f} |"
        )
    if ok:
        wall = statistics.median(r["wall_s"] for r in ok)
        cpu = statistics.median(r["cpu_s"] for r in ok)
        lines += [
            "",
            f"Median wall {wall:.1f} s, median CPU {cpu:.1f} s; {converged}/{len(rows)} converged; "
            f"target (median at most 6 s, every run converged): "
            f"{'met' if wall <= 6.0 and converged == len(rows) else 'not met'}.",
        ]
    return lines


if __name__ == "__main__":
    main()
