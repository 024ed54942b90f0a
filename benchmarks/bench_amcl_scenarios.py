"""The planner's AMCL model against nav2's AMCL beyond the scenario it was fitted on.

Each scenario is copied with ``models.range_sensor.localiser: {model: amcl}`` (the information
share fitted on building-4robots), planned with ``--accept-risk`` (the calibrated beliefs may
leave no plan within max_risk) and executed with nav2's AMCL on every robot, on the ``typical``
site. The summary of each run goes to ``amcl/scenarios/NAME.summary.md``; the table printed at
the end is the team's line of each (benchmarks/README.md, "Beliefs against nav2's AMCL").

    .venv/bin/python benchmarks/bench_amcl_scenarios.py [--sessions 2] [--only NAME ...]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_models import with_model

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "amcl" / "scenarios"
SHIPPED = ("building-4robots", "depot-jobs", "warehouse-4robots", "office-ros")
GENERATED = {"office-20rooms-4robots": ("office", 20, 4), "rack-hall-20places-4robots": ("warehouse", 20, 4)}


def amcl_copy(source: Path, target: Path) -> None:
    """``source`` with the AMCL model under its range sensor and its ROS map path made absolute."""
    with_model(source, target, "amcl")


def scenarios(tmp: Path) -> dict[str, Path]:
    """The shipped and generated scenarios, as AMCL-model copies in ``tmp``."""
    out = {}
    for name in SHIPPED:
        amcl_copy(ROOT / "configs" / f"{name}.yaml", tmp / f"{name}.yaml")
        out[name] = tmp / f"{name}.yaml"
    for name, (family, rooms, robots) in GENERATED.items():
        raw = tmp / f"{name}.raw.yaml"
        subprocess.run(
            [
                sys.executable,
                str(HERE / "families.py"),
                family,
                "--rooms",
                str(rooms),
                "--robots",
                str(robots),
                "--seed",
                "1",
                "-o",
                str(raw),
            ],
            check=True,
            capture_output=True,
        )
        amcl_copy(raw, tmp / f"{name}.yaml")
        out[name] = tmp / f"{name}.yaml"
    return out


def team_line(summary: str) -> str:
    """The consistency table's team row of a summary."""
    rows = [line for line in summary.splitlines() if line.lstrip("| ").startswith("team")]
    return rows[0] if rows else "(no team line)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=2)
    parser.add_argument("--only", nargs="*", default=None)
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        for name, path in scenarios(tmp).items():
            if args.only and name not in args.only:
                continue
            run = tmp / f"{name}.out"
            done = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "tmpnav",
                    "simulate",
                    str(path),
                    "--localiser",
                    "amcl",
                    "--sessions",
                    str(args.sessions),
                    "--accept-risk",
                    "-o",
                    str(run),
                ],
                capture_output=True,
                text=True,
            )
            if done.returncode != 0:
                print(f"{name}: exit {done.returncode}: {done.stderr.strip().splitlines()[-1:]}", flush=True)
                continue
            summary = (run / "summary.md").read_text()
            (OUT / f"{name}.summary.md").write_text(summary)
            print(f"{name}: {team_line(summary)}", flush=True)


if __name__ == "__main__":
    main()
