"""``tmpnav rooms`` on maps of 2000 x 2000 cells: the speed target of issue 22 (within 10 s).

    python benchmarks/rooms/bench_rooms.py -o benchmarks/rooms [--repeat 3]

Two generated maps of 2000 x 2000 cells of 5 cm (tests/rooms/depotgen.py, 0.2% speckles and
1% gaps in walls, the test maps' typical noise):

- ``site``: a 60 m x 30 m depot and its office in the unknown surroundings of a SLAM map, as a
  map saved after mapping one building looks;
- ``warehouse``: the whole grid is one 98 m x 94 m depot with its office (44 rows of racks), the
  worst case: every cell is segmented and the hall is split into over a hundred places.

Each map is run through the command line as a user runs it (``python -m tmpnav rooms MAP -o
scenario.yaml``, a fresh process each time, imports included) ``--repeat`` times; the median wall
time is reported, with the command's summary line and its warnings. Writes results.json and
summary.md to the output folder, with the machine (CPU model, cores, load) they were measured on.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from tests.rooms.depotgen import depot  # noqa: E402
from tests.rooms.mapgen import UNKNOWN, GeneratedMap  # noqa: E402

CELLS = 2000


def site() -> GeneratedMap:
    """A 60 m x 30 m depot (and office) in the middle of 2000 x 2000 unknown cells."""
    g = depot(0, width=60.0, height=30.0)
    rows, cols = g.pixels.shape
    top, left = (CELLS - rows) // 2, (CELLS - cols) // 2
    pixels = np.full((CELLS, CELLS), UNKNOWN, dtype=np.uint8)
    pixels[top : top + rows, left : left + cols] = g.pixels
    bottom = CELLS - top - rows  # image rows run from the top of the map down
    origin = (g.origin[0] - left * g.resolution, g.origin[1] - bottom * g.resolution)
    return GeneratedMap(pixels, g.resolution, origin, g.truth)


def warehouse() -> GeneratedMap:
    """A depot filling all 2000 x 2000 cells."""
    g = depot(0, width=98.0, height=94.0)
    assert g.pixels.shape == (CELLS, CELLS), g.pixels.shape
    return g


MAPS = {"site": site, "warehouse": warehouse}


def run(name: str, repeat: int, folder: Path) -> dict:
    map_yaml = MAPS[name]().write_ros(folder / name, name)
    times, proc = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "tmpnav", "rooms", str(map_yaml), "-o", str(folder / f"{name}.yaml")],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        times.append(time.perf_counter() - start)
        if proc.returncode != 0:
            raise SystemExit(f"{name}: tmpnav rooms failed: {proc.stderr}")
    assert proc is not None
    return {
        "map": name,
        "cells": f"{CELLS} x {CELLS}",
        "seconds": [round(t, 2) for t in times],
        "median_seconds": round(statistics.median(times), 2),
        "found": proc.stdout.strip().split(": ", 1)[1],
        "warnings": proc.stderr.strip().splitlines(),
    }


def machine() -> dict:
    lines = Path("/proc/cpuinfo").read_text().splitlines()
    model = next((line.split(":", 1)[1].strip() for line in lines if "model name" in line), platform.processor())
    return {
        "cpu": model,
        "nproc": os.cpu_count(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "python": platform.python_version(),
        "when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }


def summary(results: list[dict], where: dict) -> str:
    lines = [
        "# `tmpnav rooms` on 2000 x 2000 cell maps",
        "",
        f"Machine: {where['cpu']}, {where['nproc']} cores (`nproc`), load average {where['load_average']} "
        f"at the start, Python {where['python']}, {where['when']}.",
        "",
        "| map | median wall time (s) | runs (s) | found | warnings |",
        "|---|---|---|---|---|",
    ]
    for r in results:
        warnings = "; ".join(r["warnings"]) or "none"
        lines.append(f"| {r['map']} | {r['median_seconds']} | {r['seconds']} | {r['found']} | {warnings} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "benchmarks" / "rooms")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--only", choices=sorted(MAPS), action="append")
    args = parser.parse_args()
    where = machine()
    with tempfile.TemporaryDirectory(prefix="tmpnav-bench-rooms-") as tmp:
        results = [run(name, args.repeat, Path(tmp)) for name in (args.only or list(MAPS))]
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / "results.json").write_text(json.dumps({"machine": where, "results": results}, indent=2) + "\n")
    (args.output / "summary.md").write_text(summary(results, where))
    print(summary(results, where), end="")


if __name__ == "__main__":
    main()
