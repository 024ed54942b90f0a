"""Safety against nav2's AMCL: the plan of a scenario with the calibrated AMCL model
(``models.range_sensor.localiser: {model: amcl}``, its collision bound on the walls the robots
see), executed with nav2's AMCL on every robot on the ``typical`` site, steering as nav2's costmaps
let a robot steer (``--steer local``) and, for comparison, on the estimate alone (``--steer
estimate``). Each run's summary.md and moves.csv go to ``amcl/safety/NAME.STEER.*``; the summary's
lines on wall hits, contacts, the moves against their bounds and the beliefs against AMCL are
printed (benchmarks/README.md, "Safety against AMCL").

    .venv/bin/python benchmarks/bench_amcl_safety.py [--scenario configs/building-4robots.yaml]
        [--sessions 24] [--seed 100] [--steer local estimate] [--workers 1] [--no-recoveries] [--tag LABEL]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_amcl_scenarios import amcl_copy

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "amcl" / "safety"
#: the summary's lines this benchmark reports
KEPT = (
    "wall hits",
    "  with AMCL",
    "robot contacts",
    "moves against their bounds",
    "team ",
    "makespan",
    "localiser:",
    "nav2's recovery",
    "note:",
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", type=Path, default=ROOT / "configs" / "building-4robots.yaml")
    parser.add_argument("--sessions", type=int, default=24)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--steer", nargs="+", default=["local", "estimate"], choices=["local", "estimate"])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument(
        "--no-recoveries", action="store_true", help="without nav2's recovery behaviours (files NAME.STEER.norec.*)"
    )
    parser.add_argument(
        "--tag", default="", help="a label added to the files' names (NAME.STEER.TAG.*), so that a run keeps the others"
    )
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    name = args.scenario.stem
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        scenario = tmp / f"{name}.yaml"
        amcl_copy(args.scenario, scenario)
        for steer in args.steer:
            out = tmp / steer
            began = time.perf_counter()
            run = subprocess.run(
                [sys.executable, "-m", "tmpnav", "simulate", str(scenario), "--localiser", "amcl", "--steer", steer,
                 "--sessions", str(args.sessions), "--seed", str(args.seed), "--workers", str(args.workers), "-q",
                 *(["--no-recoveries"] if args.no_recoveries else []),
                 "--cache-dir", str(tmp / "cache"), "-o", str(out)],
                capture_output=True, text=True, cwd=ROOT,
            )  # fmt: skip
            if run.returncode != 0:
                sys.exit(f"{name} --steer {steer}: exit {run.returncode}: {run.stderr.strip()}")
            tag = f"{name}.{steer}.norec" if args.no_recoveries else f"{name}.{steer}"
            tag += f".{args.tag}" if args.tag else ""
            for part in ("summary.md", "moves.csv"):
                shutil.copyfile(out / part, OUT / f"{tag}.{part}")
            print(f"{name}, --steer {steer}, {args.sessions} sessions from seed {args.seed}, "
                  f"{time.perf_counter() - began:.0f} s:")  # fmt: skip
            for line in run.stdout.splitlines():
                if line.startswith(KEPT):
                    print("  " + line[:400])


if __name__ == "__main__":
    main()
