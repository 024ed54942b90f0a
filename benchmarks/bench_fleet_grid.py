"""Fleets against their sites: time, memory, objective and balance over robots and rooms.

    .venv/bin/python benchmarks/bench_fleet_grid.py [--kind office] [--rooms 25,50,100,200]
        [--robots 4,8,16,32] [--seeds 1-2] [--max-rooms-for-seeds 100] [--plan-args '--time-limit 600']
        [-o benchmarks/fleet/grid]

For each generated building (benchmarks/families.py: ``--kind``, rooms, robots, seed), one fresh
``tmpnav plan FILE --cache-dir EMPTY -o OUT`` with default options (and ``--plan-args``), its
processes' PSS summed and sampled every second (bench_fleet_memory.sample). Sizes past
``--max-rooms-for-seeds`` rooms run the first seed only. Where a site asks for more goal-room
assignments than tmpnav's default cap (rooms x robots > 5,000), the command runs with
``TMPNAV_MAX_GOAL_ASSIGNMENTS`` raised to that product, as a user would. Recorded per run: wall
seconds, the peak PSS, the exit code, the objective, the makespan, how the search stopped, the
rooms each robot visits (the least, and how many robots visit fewer than 3), and the stage times.
Writes runs.csv (appended), summary.md (the runs of this invocation) and grid.png (time, memory
and robots on fewer than 3 rooms against the rooms, a line per team size) into ``-o``.
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
import threading
import time
from pathlib import Path
from typing import Any

from bench_fleet_memory import ROLES, sample  # benchmarks/ is the script's folder, first on sys.path
from families import KINDS, write

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "fleet" / "grid"
#: tmpnav's default cap on a scenario's goal-room assignments (tmpnav.scenario: TMPNAV_MAX_GOAL_ASSIGNMENTS)
DEFAULT_CAP = 5000
FIELDS = (
    "kind",
    "rooms",
    "robots",
    "seed",
    "exit",
    "wall_s",
    "peak_pss_mib",
    "objective",
    "makespan_s",
    "stopped",
    "least_rooms",
    "under_3",
    "idle",
    "rooms_per_robot",
    "oracle_s",
    "planner_s",
    "bound_s",
    "load_start",
    "error",
)


def run(path: Path, rooms: int, robots: int, extra: list[str]) -> dict[str, Any]:
    """One fresh command: its wall time, peak PSS over its processes, and what plan.json says."""
    env = dict(os.environ)
    if rooms * robots > DEFAULT_CAP:
        env["TMPNAV_MAX_GOAL_ASSIGNMENTS"] = str(rooms * robots)
    with tempfile.TemporaryDirectory(prefix="tmpnav-grid-") as work:
        out = Path(work) / "out"
        command = [sys.executable, "-m", "tmpnav", "plan", str(path), "--cache-dir", str(Path(work) / "cache")]
        load = os.getloadavg()[0]
        start = time.perf_counter()
        log = Path(work) / "stderr.txt"
        with log.open("w") as stderr:
            proc = subprocess.Popen(
                [*command, *extra, "-q", "-o", str(out)], cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=stderr
            )
            ended: list[float] = []  # when the command ended, not when the sampling saw it
            waiter = threading.Thread(target=lambda: (proc.wait(), ended.append(time.perf_counter())))
            waiter.start()
            peak = 0.0
            while waiter.is_alive():
                peak = max(peak, sum(sample(proc.pid)[r] for r in ROLES))
                waiter.join(1.0)
        err = log.read_text(errors="replace")
        row: dict[str, Any] = {
            "exit": proc.returncode,
            "wall_s": round(ended[0] - start, 1),
            "peak_pss_mib": round(peak),
            "load_start": round(load, 2),
            "error": next((line for line in err.splitlines() if line.startswith("error")), ""),
        }
        plan = out / "plan.json"
        if plan.is_file():
            row.update(_plan_fields(json.loads(plan.read_text())))
    return row


def _plan_fields(doc: dict[str, Any]) -> dict[str, Any]:
    names = [r["name"] for r in doc["robots"]]
    visits = dict.fromkeys(names, 0)
    for action in doc["actions"]:
        for robot in action["robots"]:
            visits[robot] += 1
    counts = [visits[r] for r in names]
    timings = doc.get("timings", {})
    return {
        "objective": round(doc["objective"]["planner"], 3),
        "makespan_s": doc["makespan"]["planner"],
        "stopped": doc["search"].get("stopped", ""),
        "least_rooms": min(counts),
        "under_3": sum(c < 3 for c in counts),
        "idle": sum(c == 0 for c in counts),
        "rooms_per_robot": " ".join(map(str, counts)),
        "oracle_s": timings.get("oracle"),
        "planner_s": timings.get("planner"),
        "bound_s": timings.get("bound"),
    }


def summary(rows: list[dict[str, Any]], header: str) -> str:
    lines = [
        header,
        "",
        "| rooms | robots | seed | exit | wall [s] | peak PSS [MiB] | objective | makespan [s] | stopped "
        "| robots on < 3 rooms (none) | rooms per robot |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['rooms']} | {r['robots']} | {r['seed']} | {r['exit']} | {r['wall_s']} | {r['peak_pss_mib']} | "
            f"{r.get('objective', '-')} | {r.get('makespan_s', '-')} | {r.get('stopped', '-')} | "
            f"{r.get('under_3', '-')} ({r.get('idle', '-')}) | {r.get('rooms_per_robot', r.get('error', ''))} |"
        )
    walls = [r["wall_s"] for r in rows if r["exit"] == 0]
    if walls:
        lines += ["", f"{len(walls)}/{len(rows)} runs planned (exit 0); median wall {statistics.median(walls):.1f} s."]
    return "\n".join(lines) + "\n"


def plot(rows: list[dict[str, Any]], target: Path) -> None:
    """Wall time, peak PSS and the share of robots on fewer than 3 rooms against the rooms, a line
    per team size (the median over seeds; runs that did not plan left out)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    teams = sorted({r["robots"] for r in rows})
    for robots in teams:
        sizes = sorted({r["rooms"] for r in rows if r["robots"] == robots})
        pts: dict[str, list[tuple[int, float]]] = {"wall": [], "pss": [], "under": []}
        for rooms in sizes:
            done = [r for r in rows if r["robots"] == robots and r["rooms"] == rooms and r["exit"] == 0]
            if not done:
                continue
            pts["wall"].append((rooms, statistics.median(r["wall_s"] for r in done)))
            pts["pss"].append((rooms, statistics.median(r["peak_pss_mib"] for r in done) / 1024))
            pts["under"].append((rooms, statistics.median(100 * r["under_3"] / robots for r in done)))
        for ax, key in zip(axes, ("wall", "pss", "under"), strict=True):
            if pts[key]:
                ax.plot(*zip(*pts[key], strict=True), marker="o", label=f"{robots} robots")
    axes[0].set(xlabel="rooms", ylabel="wall time of a fresh tmpnav plan [s]", yscale="log", title="time")
    axes[1].set(xlabel="rooms", ylabel="peak PSS, all processes [GiB]", title="memory")
    axes[2].set(xlabel="rooms", ylabel="robots visiting fewer than 3 rooms [%]", title="balance", ylim=(-5, 105))
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Generated offices, default options, 2 cores (median over seeds)")
    fig.tight_layout()
    fig.savefig(target, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", default="office", choices=sorted(KINDS))
    parser.add_argument("--rooms", default="25,50,100,200")
    parser.add_argument("--robots", default="4,8,16,32")
    parser.add_argument("--seeds", default="1-2", help="FIRST-LAST")
    parser.add_argument("--max-rooms-for-seeds", type=int, default=100, help="larger sites: the first seed only")
    parser.add_argument("--plan-args", default="--time-limit 600", help="more options of tmpnav plan")
    parser.add_argument("-o", "--output", type=Path, default=OUT)
    args = parser.parse_args()
    first, _, last = args.seeds.partition("-")
    seeds = list(range(int(first), int(last or first) + 1))
    args.output.mkdir(parents=True, exist_ok=True)
    csv_path = args.output / "runs.csv"
    new = not csv_path.is_file()
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="tmpnav-grid-") as folder, csv_path.open("a", newline="") as f:
        out = csv.DictWriter(f, FIELDS)
        if new:
            out.writeheader()
        for rooms in (int(x) for x in args.rooms.split(",")):
            for robots in (int(x) for x in args.robots.split(",")):
                for seed in seeds if rooms <= args.max_rooms_for_seeds else seeds[:1]:
                    doc = KINDS[args.kind](rooms, robots, seed)
                    path = write(doc, Path(folder) / f"{args.kind}-{rooms}x{robots}-seed{seed}.yaml")
                    row = {"kind": args.kind, "rooms": rooms, "robots": robots, "seed": seed}
                    row.update(run(path, rooms, robots, args.plan_args.split()))
                    rows.append(row)
                    out.writerow({k: row.get(k, "") for k in FIELDS})
                    f.flush()
                    print({k: row.get(k) for k in FIELDS if k != "rooms_per_robot"}, flush=True)
    header = (
        f"# `bench_fleet_grid.py --kind {args.kind} --rooms {args.rooms} --robots {args.robots} --seeds "
        f"{args.seeds} --plan-args '{args.plan_args}'`, {started}, {os.cpu_count()} cores"
    )
    (args.output / "summary.md").write_text(summary(rows, header))
    plot(rows, args.output / "grid.png")


if __name__ == "__main__":
    main()
