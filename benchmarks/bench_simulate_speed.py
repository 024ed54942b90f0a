"""CPU seconds of one ``tmpnav simulate`` session (both configurations) in one process: the
scenario planned once (through the cache), then ``execute(report, n, seed, workers=1)`` for each
seed, timed with ``time.process_time`` and divided by ``n``; with ``--profile``, where one
session's time goes (cProfile). Results go to ``simulate_speed/`` (benchmarks/README.md,
"simulate at the planner's speed").

    .venv/bin/python benchmarks/bench_simulate_speed.py [--scenario configs/building-4robots.yaml]
        [--sessions 4] [--seeds 0 1 2 3 4] [--profile] [--label after]
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import statistics
import time
from pathlib import Path

from tmpnav.execution import execute
from tmpnav.pipeline import plan

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "simulate_speed"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, default=ROOT / "configs" / "building-4robots.yaml")
    parser.add_argument("--sessions", type=int, default=4, help="sessions per seed (their CPU time divided by it)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--profile", action="store_true", help="also profile one session (cProfile)")
    parser.add_argument("--label", default="run", help="name of the output file in simulate_speed/")
    args = parser.parse_args()
    report = plan(args.scenario)
    execute(report, 1, seed=10_000, workers=1)  # compiled functions loaded from numba's cache
    lines = [f"{args.scenario.name}: CPU s per session (both configurations), {args.sessions} sessions per seed"]
    per_session = []
    for seed in args.seeds:
        began = time.process_time()
        execute(report, args.sessions, seed=seed, workers=1)
        per_session.append((time.process_time() - began) / args.sessions)
        lines.append(f"  seed {seed}: {per_session[-1]:.3f}")
    lines.append(f"median {statistics.median(per_session):.3f} s per session; load average {_load()}")
    if args.profile:
        profile = cProfile.Profile()
        profile.enable()
        execute(report, 1, seed=args.seeds[0], workers=1)
        profile.disable()
        text = io.StringIO()
        pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(25)
        lines += ["", "one session under cProfile, by own time:", text.getvalue()]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"{args.label}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


if __name__ == "__main__":
    main()
