"""The anytime search's first plans: one cold ``tmpnav plan`` per scenario and checkout, side by
side (benchmarks/README.md, "A team's first plan from the makespan-first routes").

    .venv/bin/python benchmarks/bench_first_plans.py SCENARIO.yaml ... [--code DIR ...] [-o FILE]

Each scenario is planned with default options and an empty cache by the tmpnav of each ``--code``
checkout in turn (default: this one; another is a ``git worktree`` of an older commit, its
bytecode compiled first). One line per run: the objective, the makespan, how the search started
and stopped, the rooms of each robot, and the command's wall time. Lines are appended to FILE
(default ``first_plans/runs.txt``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def run(scenario: Path, code: Path) -> str:
    """One cold plan of ``scenario`` by the tmpnav of ``code``, as a line."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        start = time.perf_counter()
        command = ["plan", str(scenario.resolve()), "--cache-dir", f"{tmp}/cache", "-o", str(out)]
        proc = subprocess.run([sys.executable, "-m", "tmpnav", *command], cwd=code, capture_output=True, text=True)
        wall = time.perf_counter() - start
        label = f"{scenario.stem:24s} {code.name:10s}"
        if proc.returncode != 0 or not (out / "plan.json").exists():
            tail = proc.stderr.strip().splitlines()[-1:] or ["(no message)"]
            return f"{label} exit {proc.returncode} after {wall:.1f} s: {tail[0]}"
        doc = json.loads((out / "plan.json").read_text())
    search = doc["search"]
    rooms = " ".join(str(r["rooms"]) for r in doc["schedule"]["robots"].values())
    return (
        f"{label} objective {doc['objective']['name']} {doc['objective']['resimulated']:.3f}, "
        f"makespan {doc['schedule']['makespan']:.1f} s; first plan by {search.get('start', '-')}; "
        f"{search.get('stopped', '-')} after {search.get('subproblems', 0)} sub-problems; "
        f"rooms {rooms}; {wall:.1f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="+", type=Path)
    parser.add_argument("--code", type=Path, action="append", help="a checkout whose tmpnav runs (repeatable)")
    parser.add_argument("-o", "--output", type=Path, default=HERE / "first_plans" / "runs.txt")
    args = parser.parse_args()
    codes = args.code or [ROOT]
    args.output.parent.mkdir(parents=True, exist_ok=True)
    for scenario in args.scenarios:
        for code in codes:
            line = run(scenario, code.resolve())
            print(line, flush=True)
            with args.output.open("a") as f:
                f.write(line + "\n")


if __name__ == "__main__":
    main()
