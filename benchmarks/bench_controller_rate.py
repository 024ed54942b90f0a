"""The planner's RPP motions against the same law run at nav2's controller rate.

    python benchmarks/bench_controller_rate.py [SCENARIO ...] [-o FILE]

The planner evaluates nav2's Regulated Pure Pursuit law ``PLAN_SUBSTEPS`` times per control step
(``dt``, 0.5 s) and holds their mean for the step, on its arc (tmpnav.belief.pursuit.pursuit_controls);
nav2's controller server evaluates it 20 times a second (``controller_frequency``). Each
scenario is planned from an empty cache in this process, and every RPP motion the oracle rolls
out is rolled out again at dt / 10, one command a step, from the same start, on the same
shortened path: the durations (the 20 Hz one also rounded up to the plan's 0.5 s grid, which
separates the law's rate from the clock's grain) and the driven lengths, median and 10th / 90th
percentiles over the motions, and the least and largest duration ratio on the grid. It times the
two rollouts too.

Every plan here lifts the chance constraint (``--max-risk none``). A second table plans each
scenario twice more as a fresh command from an empty cache: with the planner's rollout, and
with every motion rolled out by the law at 20 Hz (``substeps=10``): the largest move's
collision bound, the plan's, and the makespan. RPP cuts the inside of bends more the faster it
runs the law, so the bounds of moves that turn by a wall or a door's jamb are where the two
differ.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import tmpnav.oracle.motions as motions
from tmpnav.belief.pursuit import PLAN_SUBSTEPS
from tmpnav.options import NO_THRESHOLD
from tmpnav.pipeline import PlanOptions, plan

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("building-4robots", "building-20", "depot-jobs", "office-ros")
#: the law's evaluations per control step at nav2's default 20 Hz with the plan's 0.5 s step
SUBSTEPS = 10


def measure(scenario: Path) -> tuple[np.ndarray, float, float]:
    """Rows (planned s, 20 Hz s, planned m, 20 Hz m) of every RPP motion planning ``scenario``
    rolls out, and the seconds the two rollouts took."""
    rows: list[tuple[float, float, float, float]] = []
    seconds = [0.0, 0.0]
    rollout = motions.pursuit_along

    def both(
        rounded,
        at,
        points,
        start_theta,
        speed,
        turn_rate,
        dt,
        params,
        clearance,
        origin,
        resolution,
        goal_heading=None,
    ):  # type: ignore[no-untyped-def]
        t0 = time.perf_counter()
        planned = rollout(rounded, at, points, start_theta, speed, turn_rate, dt, params, clearance, origin, resolution, goal_heading)  # fmt: skip  # noqa: E501
        t1 = time.perf_counter()
        fine = rollout(rounded, at, points, start_theta, speed, turn_rate, dt / SUBSTEPS, params, clearance, origin, resolution, goal_heading, substeps=1)  # fmt: skip  # noqa: E501
        seconds[0] += t1 - t0
        seconds[1] += time.perf_counter() - t1
        if planned is not None and fine is not None:
            length = [float(np.hypot(*np.diff(p.poses[:, :2], axis=0).T).sum()) for p in (planned, fine)]
            rows.append((planned.n_steps * dt, fine.n_steps * dt / SUBSTEPS, *length))
        return planned

    motions.pursuit_along = both
    try:
        with tempfile.TemporaryDirectory() as cache:
            plan(scenario, PlanOptions.of(cache_dir=cache, executor="serial", max_risk=NO_THRESHOLD))
    finally:
        motions.pursuit_along = rollout
    return np.array(rows), seconds[0], seconds[1]


#: run in a fresh interpreter (the oracle keeps its motions in memory within a process): the
#: CLI's plan with every RPP motion rolled out with argv[1] of the law per control step
_PLAN_WITH = """
import functools, sys
import tmpnav.oracle.motions as motions
from tmpnav.belief.pursuit import pursuit_along
motions.pursuit_along = functools.partial(pursuit_along, substeps=int(sys.argv.pop(1)))
from tmpnav.cli import cli
cli()
"""


def bounds(scenario: Path, substeps: int) -> tuple[float, float, float]:
    """The largest move's collision bound, the plan's, and the makespan of ``scenario`` planned
    cold in a fresh process with the chance constraint lifted, every RPP motion rolled out with
    ``substeps`` of the law per control step."""
    with tempfile.TemporaryDirectory() as cache:
        out = subprocess.run(
            [sys.executable, "-c", _PLAN_WITH, str(substeps), "plan", str(scenario), "--max-risk", "none",
             "--cache-dir", cache, "-q", "--format", "json"],
            capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
    doc = json.loads(out)
    return doc["risk"]["largest_move"], doc["risk"]["plan"], doc["makespan"]["planner"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", default=[str(ROOT / "configs" / f"{s}.yaml") for s in SCENARIOS])
    parser.add_argument("-o", "--output", type=Path, help="also write the table to this file")
    args = parser.parse_args()
    lines = [
        f"# `python benchmarks/bench_controller_rate.py`, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        "# RPP motions of a cold plan: the plan's rollout (the law's mean command a 0.5 s step) against it at 20 Hz",
        "# (median [p10, p90] over the motions; 20 Hz on the grid: its duration rounded up to 0.5 s)",
        "scenario | motions | duration, plan / 20 Hz | plan / 20 Hz on the grid | on the grid, least and largest"
        " | driven length, plan / 20 Hz | rollouts' time, plan and 20 Hz",
    ]
    for name in args.scenarios:
        rows, plan_s, fine_s = measure(Path(name))
        grid = np.ceil(rows[:, 1] / 0.5 - 1e-9) * 0.5
        cells = []
        for ratio in (rows[:, 0] / rows[:, 1], rows[:, 0] / grid, rows[:, 2] / rows[:, 3]):
            p10, p50, p90 = np.percentile(ratio, [10, 50, 90])
            cells.append(f"{p50:.3f} [{p10:.3f}, {p90:.3f}]")
        on_grid = rows[:, 0] / grid
        cells.insert(2, f"{on_grid.min():.3f}, {on_grid.max():.3f}")
        lines.append(f"{Path(name).stem} | {len(rows)} | {' | '.join(cells)} | {plan_s:.2f} s, {fine_s:.2f} s")
        print(lines[-1], flush=True)
    lines += [
        "",
        f"# cold plans, max_risk lifted: the planner's rollout ({PLAN_SUBSTEPS} of the law a step) against every motion"
        " rolled out at 20 Hz",
        "scenario | largest move's bound, plan's rollout / 20 Hz | plan's bound | makespan",
    ]
    for name in args.scenarios:
        ours, fine = bounds(Path(name), PLAN_SUBSTEPS), bounds(Path(name), SUBSTEPS)
        lines.append(
            f"{Path(name).stem} | {ours[0]:.2g} / {fine[0]:.2g} | {ours[1]:.2g} / {fine[1]:.2g}"
            f" | {ours[2]:.1f} s / {fine[2]:.1f} s"
        )
        print(lines[-1], flush=True)
    if args.output:
        args.output.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:4]), file=sys.stderr)


if __name__ == "__main__":
    main()
