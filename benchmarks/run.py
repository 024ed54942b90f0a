"""Run tmpnav's benchmarks and record the results under benchmarks/<quick|full>/.

    python benchmarks/run.py --quick    # `make bench`: a few minutes
    python benchmarks/run.py            # `make bench-full`: the recorded full runs (hours)

What is measured, each into its own folder:

- belief/: a joint two-robot EKF propagation over a 100-step path (evaluations per second)
  through the compiled kernel, the numpy batch path and the filterpy reference;
- oracle/: the cost table of 2 robots x 10 rooms (mixed encoding), cold, with 1 worker and
  with all workers: joint evaluations per second, and how many joint evaluations the
  factorisation and the pair bound saved;
- rooms-10/: the same at 10 rooms only, 5 sessions (``--only rooms10``; not in the default set);
- rooms/, robots/: ``tmpnav bench`` (paper Fig. 3(b), (c)): the default (carried beliefs),
  table costs with the anytime and with the exact search, and the paper's encoding, on the
  same goal draws;
- scale-20/, scale-40/, scale-60/, growth/, routing/: building scale (the office and the
  20-room building), and tmpnav against OR-Tools' routing on the same single-move table;
- carried/: the same tasks planned with table costs and with carried beliefs: executed
  cost, uncertainty along the way and simulated worst-case errors (benchmarks/bench_carried.py);
- simulate/: ``tmpnav simulate`` on the corridor (paper Fig. 3(a)).

Each folder gets the command that produced it (command.txt) and the machine it ran on, with
the date (machine.txt): experiments rerun one at a time (--only) keep their own record.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TMPNAV = [sys.executable, "-m", "tmpnav"]


def run(cmd: list[str], out: Path, log: Path | None = None) -> str:
    out.mkdir(parents=True, exist_ok=True)
    (out / "command.txt").write_text(" ".join(c if " " not in c else repr(c) for c in cmd[2:]) + "\n")
    (out / "machine.txt").write_text(machine())
    print("$", " ".join(cmd[1:]), flush=True)
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if log is not None:
        log.write_text(proc.stdout + proc.stderr)
    if proc.returncode != 0:
        sys.exit(f"benchmark command failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr[-2000:]}")
    return proc.stdout


def machine() -> str:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    java = subprocess.run(["java", "-version"], capture_output=True, text=True).stderr.splitlines()[:1]
    return (
        f"date: {time.strftime('%Y-%m-%d %H:%M %Z')}\ncpu: {cpu}\ncores: {os.cpu_count()}\n"
        f"python: {platform.python_version()}\nplatform: {platform.platform()}\njava: {' '.join(java)}\n"
    )


def oracle_throughput(out: Path) -> dict:
    """Cold cost table for 2 robots x 10 rooms with 1 worker and with all workers."""
    code = r"""
import json, os, sys, time
from pathlib import Path
from tmpnav.pipeline import load_world, apply_options, roadmap_for, make_oracle, Execution, Overrides
from tmpnav.oracle.table import build_table, start_locations
from tmpnav.task.encodings import ENCODINGS
from tmpnav.types import Goals
from tmpnav.bench.worker import warm_up
warm_up()
s, w = load_world("configs/corridor-2robots.yaml")
s = apply_options(s, Overrides(goals=Goals(visit=tuple(f"L{i}" for i in range(1, 11)), per_robot=())))
rm, _ = roadmap_for(s, w, None)
want = ENCODINGS["mixed"].table_request(s.goals, start_locations(s, w), 0.0)
rows = []
for workers in (1, os.cpu_count() or 1):
    for prune in (None, 0.05):
        o = make_oracle(s, w, rm, Execution(use_cache=False, executor="processes", workers=workers))
        t = time.perf_counter()
        build_table(o, w, want.destinations, want.pair_filter, pair_min_gain=prune)
        dt = time.perf_counter() - t
        o.executor.close()
        st = o.stats.sims
        rows.append({"workers": workers, "pair_min_gain_bound": prune, "seconds": round(dt, 3),
                     "pair_requests": o.stats.requests, "joint_simulations": st.joint_sims,
                     "joint_factorized": st.joint_factorized, "pairs_pruned": st.pairs_pruned,
                     "steps_spanned": st.steps_total, "steps_computed": st.steps_computed,
                     "joint_evaluations_per_s": round(st.joint_sims / dt, 1),
                     "joint_combinations_per_s": round((st.joint_sims + st.joint_factorized) / dt, 1)})
print(json.dumps(rows))
"""
    out.mkdir(parents=True, exist_ok=True)
    (out / "command.txt").write_text("python benchmarks/run.py (oracle_throughput: see benchmarks/run.py)\n")
    (out / "machine.txt").write_text(machine())
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"oracle benchmark failed:\n{proc.stderr[-2000:]}")
    rows = json.loads(proc.stdout.strip().splitlines()[-1])
    (out / "oracle.json").write_text(json.dumps(rows, indent=1) + "\n")
    lines = [
        "| workers | pair bound | seconds | joint simulations | factorised | pruned pairs | joint evals/s "
        "| EKF steps computed / spanned |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['workers']} | {r['pair_min_gain_bound']} | {r['seconds']} | {r['joint_simulations']} | "
            f"{r['joint_factorized']} | {r['pairs_pruned']} | {r['joint_evaluations_per_s']} | "
            f"{r['steps_computed']} / {r['steps_spanned']} |"
        )
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines), flush=True)
    return {"rows": rows}


def bench(
    out: Path,
    robots: str,
    rooms: str,
    sessions: str,
    timeout: str,
    variants: tuple[str, ...] = ("mixed", "paper"),
    scenario: str | None = None,
) -> None:
    """``tmpnav bench``: the variants (the first is the default) on the same goal draws."""
    cmd = [*TMPNAV, "bench", "--robots", robots, "--rooms", rooms, "--sessions", sessions, "--timeout", timeout]
    for v in variants:
        cmd += ["--encoding", v]
    if scenario is not None:
        cmd += ["--scenario", scenario]
    run([*cmd, "-o", str(out.relative_to(ROOT)), "-q"], out, out / "log.txt")


#: the variants compared at the paper's sizes: the default (carried beliefs, auto search),
#: table costs with the anytime search, the exact plan of the table (the earlier default) and
#: the paper's encoding
VARIANTS = ("mixed", "mixed:table:anytime", "mixed:table:exact", "paper")
BUILDING = "configs/building-{robots}robots.yaml"


def scale(base: Path, quick: bool) -> None:
    """Building scale: 20 rooms and 2 robots, 40 and 4, 60 and 8; the growth from 10 to 40
    rooms with 4 robots; tmpnav against OR-Tools on the 20-room building's table."""
    both = ("mixed", "mixed:table")
    bench(base / "scale-20", "2", "20", "1" if quick else "5", "600", both, "configs/building-20.yaml")
    if not quick:  # the quick version (make bench) stops at 20 rooms
        bench(base / "scale-40", "4", "40", "3", "600", both, BUILDING)
        bench(base / "scale-60", "8", "60", "2", "900", both, BUILDING)
        bench(base / "growth", "4", "10..40:10", "3", "600", ("mixed",), BUILDING)
    out = base / "routing"
    run([sys.executable, "benchmarks/bench_routing.py", "-o", str(out.relative_to(ROOT))], out, out / "log.txt")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the reduced version (make bench)")
    parser.add_argument(
        "--only", nargs="*", default=None, help="belief oracle rooms rooms10 robots scale carried simulate"
    )
    args = parser.parse_args()
    base = ROOT / "benchmarks" / ("quick" if args.quick else "full")
    only = set(args.only or ["belief", "oracle", "rooms", "robots", "scale", "carried", "simulate"])
    base.mkdir(parents=True, exist_ok=True)
    if "belief" in only:
        out = base / "belief"
        text = run([sys.executable, "benchmarks/bench_belief.py", "--repeat", "3" if args.quick else "7"], out)
        (out / "belief.json").write_text(text)
        print(text, flush=True)
    if "oracle" in only:
        oracle_throughput(base / "oracle")
    # 60 s bounds the paper encoding's runs; past it a run counts as a timeout, so the
    # speed-up at that point is a lower bound (60 s / the default's median).
    timeout = "60"
    if "rooms" in only:
        sessions, rooms = ("2", "2,10") if args.quick else ("10", "2..10:2")
        bench(base / "rooms", "2", rooms, sessions, timeout, VARIANTS)
    if "rooms10" in only:  # the issue-11 target point alone: 10 rooms, 2 robots, every variant
        bench(base / "rooms-10", "2", "10", "2" if args.quick else "5", timeout, VARIANTS)
    if "robots" in only:
        sessions, robots = ("1", "2,4") if args.quick else ("10", "2,4,6")
        bench(base / "robots", robots, "8", sessions, timeout, VARIANTS)
    if "scale" in only:
        scale(base, args.quick)
    if "carried" in only:
        out = base / "carried"
        cmd = [sys.executable, "benchmarks/bench_carried.py", "-o", str(out.relative_to(ROOT))]
        run([*cmd, "--sessions", "5" if args.quick else "25"], out, out / "log.txt")
    if "simulate" in only:
        out = base / "simulate"
        sessions = "5" if args.quick else "25"
        text = run(
            [
                *TMPNAV,
                "simulate",
                "configs/corridor.yaml",
                "--sessions",
                sessions,
                "--no-cache",
                "-o",
                str(out.relative_to(ROOT)),
                "-q",
            ],
            out,
        )
        print(text, flush=True)
    shutil.rmtree(ROOT / "benchmarks" / "tmp", ignore_errors=True)


if __name__ == "__main__":
    main()
