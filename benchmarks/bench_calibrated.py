"""A site's own calibration against held-out executions: ``tmpnav calibrate`` fits the information
share on one seed, and the plan made with the fitted line is executed again with nav2's AMCL on
another seed. Issue 55's consistency targets (a median NEES of 1-4, at most 5% of the driving steps
beyond 3 sigma) are read on the held-out steps, to the digit.

    .venv/bin/python benchmarks/bench_calibrated.py SCENARIO [SCENARIO ...] [--fit-sessions 16]
        [--fit-seed 600] [--check-sessions 16] [--check-seed 700] [--workers 2] [--refit]

Each SCENARIO (a shipped config or a generated one) gets ``amcl/calibrated/NAME.fit.yaml`` (the
calibrate output; kept and reused unless ``--refit``), ``NAME.check-seedN.csv`` (k, median NEES,
share beyond 3 sigma of the held-out steps with the plan's std scaled by k) and a line in
``amcl/calibrated/summary.txt`` (benchmarks/README.md, "A site's own calibration").
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from bench_nees_tradeoff import both_met, curve, step_nees

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "amcl" / "calibrated"


def fitted_copy(source: Path, fit: Path, target: Path) -> None:
    """``source`` with the localiser line of ``fit`` under its range sensor, its map path made absolute."""
    doc = yaml.safe_load(source.read_text())
    line = next(line for line in fit.read_text().splitlines() if line.startswith("localiser:"))
    doc["models"]["range_sensor"]["localiser"] = yaml.safe_load(line)["localiser"]
    for key in ("ros", "image"):
        value = doc.get("map", {}).get(key)
        if isinstance(value, str) and not Path(value).is_absolute():
            doc["map"][key] = str((source.parent / value).resolve())
    target.write_text(yaml.safe_dump(doc, sort_keys=False))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="+", type=Path)
    parser.add_argument("--fit-sessions", type=int, default=16)
    parser.add_argument("--fit-seed", type=int, default=600)
    parser.add_argument("--check-sessions", type=int, default=16)
    parser.add_argument("--check-seed", type=int, default=700)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--refit", action="store_true", help="run tmpnav calibrate again where a fit is kept")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    for source in (s.resolve() for s in args.scenarios):
        name = source.stem
        fit = OUT / f"{name}.fit.yaml"
        start = time.perf_counter()
        if args.refit or not fit.exists():
            subprocess.run(
                [
                    *(sys.executable, "-m", "tmpnav", "calibrate", str(source)),
                    *("--sessions", str(args.fit_sessions), "--seed", str(args.fit_seed)),
                    *("--workers", str(args.workers), "-q", "-o", str(fit)),
                ],
                cwd=ROOT,
                check=True,
                capture_output=True,
            )
        fitted = time.perf_counter()
        verdict = next(line for line in fit.read_text().splitlines() if line.startswith("# kept round"))
        with tempfile.TemporaryDirectory() as tmp:
            scenario = Path(tmp) / f"{name}.yaml"
            fitted_copy(source, fit, scenario)
            nees = step_nees(scenario, args.check_sessions, args.check_seed, args.workers)
        rows = curve(nees)
        np.savetxt(
            OUT / f"{name}.check-seed{args.check_seed}.csv",
            np.array(rows),
            delimiter=",",
            header="k,median_nees,beyond_3_sigma",
            comments="",
            fmt="%.4g",
        )
        median, beyond = float(np.median(nees)), float(np.mean(nees > 9.0))
        met = 1.0 <= median <= 4.0 and beyond <= 0.05
        line = (
            f"{name:28s} fit seed {args.fit_seed} x {args.fit_sessions} ({fitted - start:4.0f} s): "
            f"{verdict[2:].split(':')[0]}; held out seed {args.check_seed} x {args.check_sessions}: "
            f"{nees.size} steps, median NEES {median:.2f}, {100 * beyond:.1f}% beyond, "
            f"{'both met' if met else 'not both'}; scales meeting both: {both_met(rows)}"
        )
        print(line, flush=True)
        with (OUT / "summary.txt").open("a") as f:
            f.write(line + "\n")


if __name__ == "__main__":
    main()
