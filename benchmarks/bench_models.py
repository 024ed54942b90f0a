"""Every shipped config with a range sensor, planned with the sensor's bound and with the AMCL model.

Each config is planned cold (a fresh cache) as a whole command, once as shipped
(``localiser: {model: beams}`` written in, the sensor's bound) and once with
``localiser: {model: amcl}`` (nav2's AMCL at its defaults, the information share fitted by
``tmpnav calibrate``), default options otherwise: the command's wall time, its exit code, the
objective, the makespan and the rooms each robot visits. A config that ends non-zero is a
result, not a failure of the benchmark (benchmarks/README.md, "The localiser's model on every
shipped config").

    .venv/bin/python benchmarks/bench_models.py [--only NAME ...] [-o benchmarks/amcl/models.csv]
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CONFIGS = (
    "building-20",
    "building-2robots",
    "building-4robots",
    "building-8robots",
    "depot-jobs",
    "office-rooms",
    "office-ros",
    "warehouse-2robots",
    "warehouse-4robots",
    "warehouse-8robots",
)
FIELDS = ("config", "model", "exit", "wall_s", "objective", "makespan_s", "rooms_per_robot", "last_line")


def with_model(source: Path, target: Path, model: str) -> None:
    """``source`` with ``model`` under its range sensor and its ROS map path made absolute."""
    doc = yaml.safe_load(source.read_text())
    ros = doc.get("map", {}).get("ros")
    if ros and not Path(ros).is_absolute():
        doc["map"]["ros"] = str((source.parent / ros).resolve())
    doc["models"]["range_sensor"]["localiser"] = {"model": model}
    target.write_text(yaml.safe_dump(doc, sort_keys=False))


def plan(scenario: Path, work: Path) -> dict[str, object]:
    """One cold ``tmpnav plan`` of ``scenario``: its exit, wall time and plan."""
    cache, out = work / "cache", work / "out"
    shutil.rmtree(cache, ignore_errors=True)
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", str(scenario), "--cache-dir", str(cache), "-o", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    row: dict[str, object] = {"exit": done.returncode, "wall_s": round(wall, 2)}
    lines = (done.stderr + done.stdout).strip().splitlines()
    row["last_line"] = lines[-1][:160] if done.returncode and lines else ""
    if (out / "plan.json").exists():
        doc = json.loads((out / "plan.json").read_text())
        row["objective"] = round(float(doc["objective"]["planner"]), 3)
        row["makespan_s"] = doc["makespan"]["planner"]
        rooms = {r["name"]: 0 for r in doc["robots"]}
        for action in doc["actions"]:
            for move in action["moves"]:
                rooms[move["robot"]] += 1
        row["rooms_per_robot"] = " ".join(str(v) for v in rooms.values())
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", default=list(CONFIGS))
    parser.add_argument("-o", "--output", type=Path, default=HERE / "amcl" / "models.csv")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name in args.only:
            for model in ("beams", "amcl"):
                scenario = work / f"{name}.{model}.yaml"
                with_model(ROOT / "configs" / f"{name}.yaml", scenario, model)
                row = {"config": name, "model": model, **plan(scenario, work)}
                rows.append(row)
                print(", ".join(f"{k} {row.get(k, '')}" for k in FIELDS if k != "last_line"), row["last_line"])
    with args.output.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
