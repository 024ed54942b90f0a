"""The default objective against a run with ten times the budget, on the median seed of a family.

    .venv/bin/python benchmarks/bench_budget.py [--sizes office:40:4,office:60:8]

For every size (kind, rooms, robots), the median seed by objective of the last families run
(benchmarks/families/runs.csv, written by benchmarks/bench_families.py) is generated again
(benchmarks/families.py) and planned twice as a fresh ``tmpnav plan``, a cold cache each: with
its default budget (tmpnav.choices.work_budget: 2 sub-problems per goal room and robot) and with
``--anytime-work`` ten times that. The 10x run is the reference of the default objective
(the issue's "a 10x budget run as the reference for the default objective"). Writes
benchmarks/budget/budget.txt and prints it.
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from families import KINDS, write  # benchmarks/ is the script's folder, first on sys.path

from tmpnav.choices import work_budget

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "budget"
TMPNAV = [sys.executable, "-m", "tmpnav"]


def median_seed(kind: str, rooms: int, robots: int) -> int:
    """The seed whose objective is the median of the families run (the lower middle one)."""
    with open(ROOT / "benchmarks" / "families" / "runs.csv") as fh:
        rows = [
            r
            for r in csv.DictReader(fh)
            if (r["kind"], int(r["rooms"]), int(r["robots"])) == (kind, rooms, robots) and r["exit"] == "0"
        ]
    if not rows:
        sys.exit(f"no run of {kind} {rooms}/{robots} in benchmarks/families/runs.csv: run bench_families.py first")
    rows.sort(key=lambda r: float(r["objective"]))
    return int(rows[(len(rows) - 1) // 2]["seed"])


def plan(scenario: Path, cache: Path, extra: list[str]) -> tuple[float, str, float]:
    """One fresh command: its objective, where the search stopped, its seconds."""
    start = time.perf_counter()
    proc = subprocess.run(
        [*TMPNAV, "plan", str(scenario), "--cache-dir", str(cache), *extra],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        sys.exit(f"{scenario.name} {extra} failed ({proc.returncode}): {proc.stderr.strip()[-400:]}")
    objective = re.search(r"objective .*?: ([0-9.]+)", proc.stdout)
    stopped = re.search(r"stopped: ([a-z ]+)", proc.stdout)
    assert objective is not None
    return float(objective.group(1)), stopped.group(1).strip() if stopped else "exact", seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="office:40:4,office:60:8", help="kind:rooms:robots, comma-separated")
    args = parser.parse_args()
    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        for field in args.sizes.split(","):
            kind, rooms, robots = field.split(":")[0], int(field.split(":")[1]), int(field.split(":")[2])
            seed = median_seed(kind, rooms, robots)
            scenario = write(KINDS[kind](rooms, robots, seed), Path(tmp) / f"{kind}-{rooms}-{robots}-{seed}.yaml")
            budget = work_budget(rooms, robots, None)
            runs = {}
            for label, extra in (("default", []), ("10x", ["--anytime-work", f"{10 * budget}"])):
                runs[label] = plan(scenario, Path(tmp) / f"cache-{label}-{seed}", extra)
            (d, d_stop, d_s), (r, r_stop, r_s) = runs["default"], runs["10x"]
            lines.append(
                f"{kind} {rooms} rooms / {robots} robots, median seed {seed}: default budget {budget} sub-problems "
                f"{d:.3f} ({d_stop}, {d_s:.1f} s); 10x budget {10 * budget} {r:.3f} ({r_stop}, {r_s:.1f} s); "
                f"default {100 * (d - r) / r:+.2f}% against the 10x run"
            )
            print(lines[-1], flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    stamp = f"# `python benchmarks/bench_budget.py --sizes {args.sizes}`, {when}\n"
    (OUT / "budget.txt").write_text(stamp + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
