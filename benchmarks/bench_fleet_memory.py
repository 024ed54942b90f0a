"""Where a fleet's run holds its memory: PSS by process, sampled through a fresh ``tmpnav plan``.

    .venv/bin/python benchmarks/bench_fleet_memory.py [--sizes office:100:16] [--seeds 1-3]
        [--code DIR] [--label NAME] [--interval 1] [--plan-args '--time-limit 600']
        [-o benchmarks/fleet/memory.txt]

For each generated building (benchmarks/families.py: kind, rooms, robots) and seed, one fresh
``tmpnav plan FILE --cache-dir EMPTY -o OUT`` with default options (``--code DIR``: the tmpnav of
another checkout, run as ``python -m tmpnav`` from DIR). Every ``--interval`` seconds it sums the
proportional set size (PSS, /proc/PID/smaps_rollup) of the command's processes by role: the
command itself, its oracle workers (the pool's children), the lower bound's forked process and
ENHSP's JVM. Appends to the output one row per run: the peak of the sum, each role's value at
that peak, when it came (seconds into the run), the largest value of each role over the run,
the wall time, the exit code and the plan's objective, so that two codes run in turn compare.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from families import KINDS, write  # noqa: E402

ROLES = ("main", "workers", "bound", "jvm", "other")


def _children(pid: int) -> list[int]:
    out: list[int] = []
    try:
        for task in Path(f"/proc/{pid}/task").iterdir():
            out += [int(c) for c in (task / "children").read_text().split()]
    except OSError:
        pass
    return out


def _pss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Pss:"):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError):
        pass
    return 0.0


def _role(pid: int, root: int) -> str:
    if pid == root:
        return "main"
    try:
        command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        name = Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        return "gone"
    if "java" in command:
        return "jvm"
    # both fork the command; each names itself (tmpnav.oracle.executors.name_process)
    return {"tmpnav-bound": "bound", "tmpnav-oracle": "workers"}.get(name, "other")


def sample(root: int) -> dict[str, float]:
    """PSS (MB) of each role among the processes under ``root``."""
    by = dict.fromkeys(ROLES, 0.0)
    todo = [root]
    while todo:
        pid = todo.pop()
        todo += _children(pid)
        role = _role(pid, root)
        if role in by:
            by[role] += _pss_mb(pid)
    return by


def run(scenario: Path, code: Path, interval: float, extra: list[str]) -> dict[str, object]:
    """One fresh command; the peak of its PSS and each role's share then, its time and plan."""
    with tempfile.TemporaryDirectory(prefix="tmpnav-memory-") as work:
        out = Path(work) / "out"
        command = [sys.executable, "-m", "tmpnav", "plan", str(scenario), "--cache-dir", str(Path(work) / "cache")]
        start = time.perf_counter()
        proc = subprocess.Popen([*command, *extra, "-q", "-o", str(out)], cwd=code, stdout=subprocess.DEVNULL)
        peak: dict[str, float] = dict.fromkeys(ROLES, 0.0)
        most = dict.fromkeys(ROLES, 0.0)
        at = 0.0
        while proc.poll() is None:
            now = sample(proc.pid)
            for role in ROLES:
                most[role] = max(most[role], now[role])
            if sum(now.values()) > sum(peak.values()):
                peak, at = now, time.perf_counter() - start
            time.sleep(interval)
        wall = time.perf_counter() - start
        objective = None
        if (out / "plan.json").is_file():
            objective = json.loads((out / "plan.json").read_text())["objective"]["planner"]
    return {"peak": peak, "at": at, "most": most, "wall": wall, "exit": proc.returncode, "objective": objective}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="office:100:16", help="KIND:ROOMS:ROBOTS, comma-separated")
    parser.add_argument("--seeds", default="1-3", help="FIRST-LAST")
    parser.add_argument("--code", type=Path, default=ROOT, help="the checkout whose tmpnav runs")
    parser.add_argument("--label", default="this checkout")
    parser.add_argument("--interval", type=float, default=1.0, help="seconds between samples")
    parser.add_argument("--plan-args", default="", help="more options of tmpnav plan, e.g. '--time-limit 600'")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "benchmarks" / "fleet" / "memory.txt")
    args = parser.parse_args()
    first, _, last = args.seeds.partition("-")
    seeds = range(int(first), int(last or first) + 1)
    rows = []
    with tempfile.TemporaryDirectory(prefix="tmpnav-fleet-") as folder:
        for size in args.sizes.split(","):
            kind, rooms, robots = size.split(":")
            for seed in seeds:
                doc = KINDS[kind](int(rooms), int(robots), seed)
                path = write(doc, Path(folder) / f"{kind}-{rooms}x{robots}-seed{seed}.yaml")
                load = os.getloadavg()[0]
                r = run(path, args.code.resolve(), args.interval, args.plan_args.split())
                peak, most = r["peak"], r["most"]
                assert isinstance(peak, dict) and isinstance(most, dict)
                shares = " ".join(f"{role} {peak[role]:.0f}" for role in ROLES)
                tops = " ".join(f"{role} {most[role]:.0f}" for role in ROLES)
                rows.append(
                    f"| {args.label} | {kind} {rooms} x {robots} | {seed} | {sum(peak.values()):.0f} MB "
                    f"at {r['at']:.0f} s ({shares}) | {tops} | {r['wall']:.1f} s | {r['exit']} | "
                    f"{r['objective']} | {load:.1f} |"
                )
                print(rows[-1], flush=True)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with args.output.open("a") as f:
        f.write(
            f"# bench_fleet_memory.py --sizes {args.sizes} --seeds {args.seeds} --plan-args '{args.plan_args}' "
            f"({args.label}), "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} cores\n"
            "| code | building | seed | peak PSS (MB by role then) | each role's most (MB) | wall | exit | objective "
            "| load before |\n"
        )
        f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
