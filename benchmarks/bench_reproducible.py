"""The same plan on an idle machine and beside two CPU-bound processes, for shipped configs.

    .venv/bin/python benchmarks/bench_reproducible.py [--configs corridor,building-20]

Each config is planned as a fresh ``tmpnav plan --no-cache --format json`` with default options,
first alone, then with two ``python -c 'while 1: pass'`` processes beside it (one per core of a
2-core machine). The two plan.json documents are compared with the timings left out (the stage
times, the search's seconds and the times of its improvements). Writes
benchmarks/reproducible/reproducible.txt and prints it.
"""

from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from tmpnav.report.plan_json import without_timings

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "reproducible"
TMPNAV = [sys.executable, "-m", "tmpnav"]
#: the shipped configs up to building-20's size (20 goal rooms, 2 robots)
CONFIGS = (
    "two-rooms",
    "corridor",
    "corridor-2robots",
    "corridor-3robots",
    "office-ros",
    "sparse-warehouse",
    "warehouse-2robots",
    "depot-jobs",
    "building-2robots",
    "building-20",
)


def plan(config: str) -> tuple[dict[str, Any] | None, float, str]:
    """plan.json of one fresh command (None if it failed), its seconds, its stderr's last line."""
    start = time.perf_counter()
    proc = subprocess.run(
        [*TMPNAV, "plan", f"configs/{config}.yaml", "--no-cache", "--format", "json", "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - start
    last = (proc.stderr.strip().splitlines() or [""])[-1]
    return (json.loads(proc.stdout) if proc.returncode == 0 else None), seconds, last


def loaded(config: str) -> tuple[dict[str, Any] | None, float, str]:
    """:func:`plan` with two CPU-bound processes beside it."""
    hogs = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(2)]
    try:
        return plan(config)
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def describe(doc: dict[str, Any] | None, seconds: float, error: str) -> str:
    if doc is None:
        return f"failed in {seconds:.1f} s ({error})"
    s = doc["search"]
    capped = f", capped by {'; '.join(s['capped'])}" if s.get("capped") else ""
    objective = doc["objective"]["resimulated"]
    return f"{objective:.3f}, {s['mode']} {s['stopped']} after {s['subproblems']} sub-problems{capped}, {seconds:.1f} s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", default=",".join(CONFIGS))
    args = parser.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [f"# `python benchmarks/bench_reproducible.py`, {now}, commit {commit.stdout.strip()}"]
    print(lines[0], flush=True)
    for config in args.configs.split(","):
        idle, idle_s, idle_err = plan(config)
        busy, busy_s, busy_err = loaded(config)
        same = idle is not None and busy is not None and without_timings(idle) == without_timings(busy)
        line = (
            f"{config}: idle {describe(idle, idle_s, idle_err)}; loaded {describe(busy, busy_s, busy_err)}; "
            f"plan.json {'the same' if same else 'DIFFERENT'} (timings aside)"
        )
        print(line, flush=True)
        lines.append(line)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "reproducible.txt").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
