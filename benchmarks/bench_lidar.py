"""Robots that see the walls: the range sensor's figures (docs/models.md, "Range sensor").

    .venv/bin/python benchmarks/bench_lidar.py corridor            # the featureless corridor (figure)
    .venv/bin/python benchmarks/bench_lidar.py time [--runs 1]      # plan time with and without the lidar
    .venv/bin/python benchmarks/bench_lidar.py simulate [--sessions 200]   # 200 executions of building-4robots
    .venv/bin/python benchmarks/bench_lidar.py kernel              # the EKF's cost per control step

Each writes its results to benchmarks/lidar/ (``corridor.txt``, ``time.txt``, ``simulate.txt``) and
prints them; ``corridor`` also draws docs/figures/lidar-corridor.png.

* corridor: a robot drives 60 m along a corridor 2 m wide with no door and no feature, with a 12 m
  lidar (tmpnav's compiled kernel, maximum-likelihood observations): its position std along
  and across the corridor at every metre.
* time: fresh ``tmpnav plan`` commands (a cold cache each) of building-20, building-4robots and
  building-4robots with 40 goal rooms, with the scenario's lidar and with ``--no-range-sensor``,
  one after the other, alternating which goes first.
* simulate: ``tmpnav simulate configs/building-4robots.yaml --sessions N``, with the lidar and
  without (the paper's model): worst-case errors, NEES, wall hits and robot contacts.
* kernel: the compiled EKF's time per control step of two robots (joint state of 6), with three
  landmarks in view, with and without a scan at every step: the best of 9 interleaved repeats of
  1,000 simulations of 100 steps each.
"""

from __future__ import annotations

import argparse
import math
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "lidar"
TMPNAV = [sys.executable, "-m", "tmpnav"]


def corridor() -> str:
    from tmpnav.belief.rollout import Rollout, propagate_rollout
    from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor, RangeSensor
    from tmpnav.world.grid import OccupancyGrid
    from tmpnav.world.lidar import signed_distance
    from tmpnav.world.scan_information import ScanInformation

    res, length, width, dt, speed = 0.05, 64.0, 2.0, 0.5, 0.5
    rows, cols = round((width + 0.3) / res), round((length + 0.3) / res)
    occupied = np.zeros((rows, cols), dtype=bool)
    occupied[:3], occupied[-3:], occupied[:, :3], occupied[:, -3:] = True, True, True, True
    grid = OccupancyGrid(occupied, (0.0, 0.0), res)
    lidar = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01)
    table = ScanInformation(grid, signed_distance(grid), lidar)
    T = int((length - 4.0) / (speed * dt))
    x = 2.0 + speed * dt * np.arange(T + 1)
    poses = np.column_stack([x, np.full(T + 1, rows * res / 2), np.zeros(T + 1)])
    rows_of = table.rows(table.keys(poses))
    scans = table.table[rows_of]
    sensor = RangeBearingSensor(5.0, 2 * math.pi, 0.1, math.radians(3))
    models = Models(dt, (0.01, 0.0, 0.02, 0.01), sensor, sensor, False, ObservationMode.MAX_LIKELIHOOD, 0, lidar)
    none = np.zeros((1, T + 1, 0), dtype=bool)
    rollout = Rollout(np.tile([speed, 0.0], (1, T, 1)), poses[None], np.array([T]), none, np.zeros((1, 1, T + 1), bool))
    start = Belief(poses[0].copy(), np.diag([0.01, 0.01, 0.001]))
    runs = {
        "lidar": propagate_rollout(start, replace(rollout, scans=scans[None]), np.zeros((0, 2)), models),
        "none": propagate_rollout(start, rollout, np.zeros((0, 2)), replace(models, range_sensor=None)),
    }
    along, across = np.sqrt(runs["lidar"].covs[:, 0, 0]), np.sqrt(runs["lidar"].covs[:, 1, 1])
    lines = [
        "featureless corridor 64 m x 2 m (walls 0.15 m), robot from x = 2 to 62 m at 0.5 m/s, dt 0.5 s,",
        "lidar 12 m / 360 deg / 60 beams / sigma 0.03 m / max incidence 75 deg / divergence 0.01,",
        "motion noise (0.01, 0, 0.02, 0.01),",
        "start std 0.1 m, 0.032 rad; the kernel in maximum-likelihood mode (the covariance does not depend on noise)",
        "x [m]   std along [m]   std across [m]   (no sensor: std along, across [m])",
    ]
    plain = runs["none"].covs
    for k in range(0, T + 1, round(4.0 / (speed * dt))):
        lines.append(
            f"{x[k]:5.1f}   {along[k]:12.4f}   {across[k]:13.4f}   "
            f"({math.sqrt(plain[k, 0, 0]):.3f}, {math.sqrt(plain[k, 1, 1]):.3f})"
        )
    lines.append(
        f"largest std across after the first scan: {across[1:].max():.4f} m; largest std along: {along.max():.3f} m"
    )
    ends = (0.15 + lidar.range, cols * res - 0.15 - lidar.range)  # where an end wall leaves the range
    _figure(x, along, across, np.sqrt(plain[:, 0, 0]), np.sqrt(plain[:, 1, 1]), ends)
    return "\n".join(lines)


def _figure(
    x: np.ndarray,
    along: np.ndarray,
    across: np.ndarray,
    along0: np.ndarray,
    across0: np.ndarray,
    ends: tuple[float, float],
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 3.6))
    ax.semilogy(x, along, color="#1f77b4", lw=2, label="lidar: std along the corridor")
    ax.semilogy(x, across, color="#d62728", lw=2, label="lidar: std across the corridor")
    ax.semilogy(x, along0, color="#1f77b4", lw=1, ls="--", label="no sensor: along")
    ax.semilogy(x, across0, color="#d62728", lw=1, ls="--", label="no sensor: across")
    for end in ends:
        ax.axvline(end, color="grey", lw=0.8, ls=":")
    ax.text(sum(ends) / 2, 2e-3, "both ends beyond the 12 m range", ha="center", fontsize=8, color="grey")
    ax.set_xlabel("x along the corridor [m]")
    ax.set_ylabel("position std [m]")
    ax.set_title("A 60 m featureless corridor, 12 m lidar: pinned across, aliased along", fontsize=10)
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    fig.tight_layout()
    fig.savefig(ROOT / "docs" / "figures" / "lidar-corridor.png", dpi=110)


def forty_rooms(folder: Path) -> Path:
    """building-4robots with 40 goal rooms spread over its corridors."""
    source = ROOT / "configs" / "building-4robots.yaml"
    doc = yaml.safe_load(source.read_text())
    names = sorted((r["name"] for r in doc["rooms"]), key=lambda n: (n[0], int(n[1:])))
    doc["goals"] = {"visit": [names[round(k * (len(names) - 1) / 39)] for k in range(40)]}
    doc["name"] = "building-4robots-40rooms"
    target = folder / "building-4robots-40rooms.yaml"
    target.write_text(yaml.safe_dump(doc, sort_keys=False))
    return target


def _plan_seconds(scenario: Path, lidar: bool, cache: Path) -> tuple[float, str]:
    cmd = [*TMPNAV, "plan", str(scenario), "--cache-dir", str(cache), "-q", "--format", "text"]
    if not lidar:
        cmd.append("--no-range-sensor")
    start = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr[-800:]}")
    objective = re.search(r"objective .*?: ([0-9.]+)", proc.stdout)
    std = re.findall(r"(\d+\.\d+) / \d+\.\d+ m", proc.stdout)
    return seconds, f"objective {objective.group(1) if objective else '?'}, largest std {max(map(float, std)):.2f} m"


def timing(runs: int) -> str:
    lines = ["fresh `tmpnav plan` commands, a cold cache each; seconds (with the lidar / --no-range-sensor)"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        cases = {
            "building-20": ROOT / "configs" / "building-20.yaml",
            "building-4robots": ROOT / "configs" / "building-4robots.yaml",
            "40 rooms / 4 robots": forty_rooms(folder),
        }
        for name, scenario in cases.items():
            with_s, without_s, notes = [], [], {}
            for k in range(runs):
                order = (True, False) if k % 2 == 0 else (False, True)
                for lidar in order:
                    cache = folder / f"cache-{name}-{k}-{lidar}".replace(" ", "_").replace("/", "")
                    seconds, note = _plan_seconds(scenario, lidar, cache)
                    (with_s if lidar else without_s).append(seconds)
                    notes[lidar] = note
            ratio = np.median(with_s) / np.median(without_s)
            lines.append(
                f"{name}: lidar {', '.join(f'{s:.2f}' for s in with_s)} s ({notes[True]}); "
                f"without {', '.join(f'{s:.2f}' for s in without_s)} s ({notes[False]}); ratio {ratio:.2f}"
            )
            print(lines[-1], flush=True)
    return "\n".join(lines)


def simulate(sessions: int) -> str:
    lines = []
    for label, extra in (
        ("with the lidar", []),
        ("without (--no-range-sensor, the paper's model)", ["--no-range-sensor"]),
    ):
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [
                *TMPNAV,
                "simulate",
                "configs/building-4robots.yaml",
                "--sessions",
                str(sessions),
                "-q",
                "--cache-dir",
                tmp,
                *extra,
            ]
            start = time.perf_counter()
            proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
            if proc.returncode != 0:
                sys.exit(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr[-800:]}")
            lines += [f"## {label}: {' '.join(cmd[2:])} ({time.perf_counter() - start:.0f} s)", proc.stdout.strip(), ""]
            print("\n".join(lines[-3:]), flush=True)
    return "\n".join(lines)


def kernel() -> str:
    from tmpnav.belief.rollout import ObservationNoise, Rollout, propagate_rollout
    from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor, RangeSensor

    rng = np.random.default_rng(0)
    n, T, L = 2, 100, 3
    poses = np.zeros((n, T + 1, 3))
    poses[:, :, 0] = np.linspace(0.0, 25.0, T + 1)
    poses[1, :, 1] = 2.0
    visible = np.ones((n, T + 1, L), dtype=bool)
    mutual = np.zeros((n, n, T + 1), dtype=bool)
    scans = rng.normal(0.0, 30.0, (n, T + 1, 3, 3))
    rollout = Rollout(np.tile([0.5, 0.0], (n, T, 1)), poses, np.array([T, T]), visible, mutual)
    sensor = RangeBearingSensor(5.0, 2 * math.pi, 0.1, math.radians(3))
    lidar = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01)
    models = Models(0.5, (0.01, 0.0, 0.02, 0.01), sensor, sensor, True, ObservationMode.NOISY, 0)
    landmarks = rng.uniform(0.0, 25.0, (L, 2))
    noise = ObservationNoise.draw(0, n, T, L)
    start = Belief(np.zeros(3 * n), np.eye(3 * n) * 0.01)
    lines = ["compiled kernel, 2 robots, 100 steps, 3 landmarks in view at every step; microseconds per step"]
    variants = {
        "landmarks and partners": (rollout, models),
        "with a scan per robot and step": (replace(rollout, scans=scans), replace(models, range_sensor=lidar)),
    }
    best = dict.fromkeys(variants, math.inf)
    for rollout_, models_ in variants.values():
        propagate_rollout(start, rollout_, landmarks, models_, noise)  # compiled
    for _ in range(9):  # the two interleaved: a busy moment slows both
        for label, (rollout_, models_) in variants.items():
            t0 = time.perf_counter()
            for _ in range(1000):
                propagate_rollout(start, rollout_, landmarks, models_, noise)
            best[label] = min(best[label], time.perf_counter() - t0)
    per_step = {label: seconds / (1000 * T) * 1e6 for label, seconds in best.items()}
    for label, us in per_step.items():
        lines.append(f"{label}: {us:.2f} us per step (whole calls, layout included; best of 9 interleaved)")
    ratio = per_step["with a scan per robot and step"] / per_step["landmarks and partners"]
    lines.append(f"ratio {ratio:.2f}")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("corridor", "time", "simulate", "kernel"))
    parser.add_argument("--runs", type=int, default=1, help="time: runs of each case, with and without")
    parser.add_argument("--sessions", type=int, default=200, help="simulate: executions")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if args.what == "corridor":
        text = corridor()
    elif args.what == "time":
        text = timing(args.runs)
    elif args.what == "kernel":
        text = kernel()
    else:
        text = simulate(args.sessions)
    stamp = f"# {' '.join(sys.argv[1:])}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n"
    (OUT / f"{'time' if args.what == 'time' else args.what}.txt").write_text(stamp + text + "\n")
    print(text)


if __name__ == "__main__":
    main()
