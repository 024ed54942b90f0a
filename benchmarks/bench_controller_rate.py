"""The planner's RPP motions against the same law run at nav2's controller rate.

    python benchmarks/bench_controller_rate.py [SCENARIO ...] [-o FILE]

The planner evaluates nav2's Regulated Pure Pursuit law once per control step (``dt``, 0.5 s:
tmpnav.belief.pursuit.pursuit_controls); nav2's controller server evaluates it 20 times a second
(``controller_frequency``). Each scenario is planned from an empty cache in this process, and
every RPP motion the oracle rolls out is rolled out again at dt / 10 from the same start, on
the same shortened path: the durations (the 20 Hz one also rounded up to the plan's 0.5 s grid,
which separates the law's rate from the clock's grain) and the driven lengths, median and
10th / 90th percentiles over the motions. It times the two rollouts too.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import tmpnav.oracle.motions as motions
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
    rollout = motions.pursuit_controls

    def both(
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
        required=None,
    ):  # type: ignore[no-untyped-def]  # noqa: E501
        t0 = time.perf_counter()
        planned = rollout(points, start_theta, speed, turn_rate, dt, params, clearance, origin, resolution, goal_heading, required)  # fmt: skip  # noqa: E501
        t1 = time.perf_counter()
        fine = rollout(points, start_theta, speed, turn_rate, dt / SUBSTEPS, params, clearance, origin, resolution, goal_heading, required)  # fmt: skip  # noqa: E501
        seconds[0] += t1 - t0
        seconds[1] += time.perf_counter() - t1
        if planned is not None and fine is not None:
            length = [float(np.hypot(*np.diff(p.poses[:, :2], axis=0).T).sum()) for p in (planned, fine)]
            rows.append((planned.n_steps * dt, fine.n_steps * dt / SUBSTEPS, *length))
        return planned

    motions.pursuit_controls = both
    try:
        with tempfile.TemporaryDirectory() as cache:
            plan(scenario, PlanOptions.of(cache_dir=cache, executor="serial"))
    finally:
        motions.pursuit_controls = rollout
    return np.array(rows), seconds[0], seconds[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", default=[str(ROOT / "configs" / f"{s}.yaml") for s in SCENARIOS])
    parser.add_argument("-o", "--output", type=Path, help="also write the table to this file")
    args = parser.parse_args()
    lines = [
        f"# `python benchmarks/bench_controller_rate.py`, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        "# RPP motions of a cold plan: the plan's rollout (the law once per 0.5 s step) against the law at 20 Hz",
        "# (median [p10, p90] over the motions; 20 Hz on the grid: its duration rounded up to 0.5 s)",
        "scenario | motions | duration, plan / 20 Hz | plan / 20 Hz on the grid | driven length, plan / 20 Hz"
        " | rollouts' time, plan and 20 Hz",
    ]
    for name in args.scenarios:
        rows, plan_s, fine_s = measure(Path(name))
        grid = np.ceil(rows[:, 1] / 0.5 - 1e-9) * 0.5
        cells = []
        for ratio in (rows[:, 0] / rows[:, 1], rows[:, 0] / grid, rows[:, 2] / rows[:, 3]):
            p10, p50, p90 = np.percentile(ratio, [10, 50, 90])
            cells.append(f"{p50:.3f} [{p10:.3f}, {p90:.3f}]")
        lines.append(f"{Path(name).stem} | {len(rows)} | {' | '.join(cells)} | {plan_s:.2f} s, {fine_s:.2f} s")
        print(lines[-1], flush=True)
    if args.output:
        args.output.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:4]), file=sys.stderr)


if __name__ == "__main__":
    main()
