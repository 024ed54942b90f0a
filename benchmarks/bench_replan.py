"""Replan latency (issue 43): seeded random events on a shipped scenario's plan, each replanned
with `tmpnav.replan.replan` on a warm cache (the first plan's), the old plan as incumbent.

    python benchmarks/bench_replan.py --scenario configs/building-20.yaml --events 20 -o benchmarks/replan

An event happens at a random time of the plan's makespan and is one of: nothing but the team's
state then (the robots where the plan has them), a robot down (never the last), a goal not yet
done removed, a room added as a goal, a door of a goal room not yet done closed. Each replan runs
in this process after the first plan (imports and the compiled kernels are warm, as in a planning
service); its latency is the wall time of `replan`, the roadmap grown again for the new starts
included. Writes `<name>.csv` (one row per event) and `<name>.txt` (median, p90, max) to -o.

`--anytime-budget S` gives the replans (not the first plan) that run budget: the same events,
seed for seed, trade latency for the objective (each replan's is in the CSV); the files are then
`<name>-budget<S>.csv` and `.txt`.
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tmpnav.errors import TmpnavError  # noqa: E402
from tmpnav.pipeline import PlanOptions, load_world, plan  # noqa: E402
from tmpnav.replan import replan  # noqa: E402
from tmpnav.replan.state import TeamState  # noqa: E402
from tmpnav.report.plan_json import plan_document  # noqa: E402
from tmpnav.report.schedule import objective_values  # noqa: E402

KINDS = ("state", "down", "remove", "add", "door")


def event(rng: random.Random, doc: dict, scenario_rooms: list[str], doors: dict[str, str], path: Path) -> TeamState:
    """A random event on the plan ``doc`` (see the module docstring)."""
    t = round(rng.uniform(0.0, doc["schedule"]["makespan"]), 1)
    robots = sorted(doc["trajectories"])
    done = {m["to"] for e in doc["schedule"]["robots"].values() for m in e["moves"] if m["end"] <= t}
    goals = [m["to"] for a in doc["actions"] for m in a["moves"] if m["to"] not in done]
    kind = rng.choice(KINDS)
    if kind == "down" and len(robots) > 1:
        from tmpnav.replan.state import RobotState

        r = rng.choice(robots)
        return TeamState(path, t, robots={r: RobotState(r, down=True)})
    if kind == "remove" and len(goals) > 1:
        return TeamState(path, t, remove=(rng.choice(goals),))
    if kind == "add":
        spare = [x for x in scenario_rooms if x not in goals and x not in done]
        if spare:
            return TeamState(path, t, add=(rng.choice(spare),))
    if kind == "door":
        shut = [d for d, room in doors.items() if room in goals]
        if shut:
            return TeamState(path, t, doors={rng.choice(shut): False})
    return TeamState(path, t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--events", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--anytime-budget", type=float, default=None, help="the replans' run budget (s)")
    ap.add_argument("-o", "--output", type=Path, required=True)
    args = ap.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    name = Path(args.scenario).stem + ("" if args.anytime_budget is None else f"-budget{args.anytime_budget:g}")
    cache = Path(tempfile.mkdtemp(prefix="tmpnav-replan-bench-"))
    options = PlanOptions.of(cache_dir=cache)
    t0 = time.perf_counter()
    first = plan(args.scenario, options)
    first_s = time.perf_counter() - t0
    doc = json.loads(json.dumps(plan_document(first)))
    plan_path = cache / "plan0.json"
    plan_path.write_text(json.dumps(doc))
    sc = first.scenario
    rooms = [r.name for r in sc.rooms]
    doors = {}
    for d in sc.doors:  # the room each door opens into: the room whose polygon holds its midpoint, nudged
        (x0, y0), (x1, y1) = d.segment
        mid = ((x0 + x1) / 2, (y0 + y1) / 2)
        for dx, dy in ((0, 0.3), (0, -0.3), (0.3, 0), (-0.3, 0)):
            room = first.world.room_of([mid[0] + dx, mid[1] + dy])
            if room is not None and room in [g for g in sc.goals.all_rooms]:
                doors[d.name] = room
                break
    rng = random.Random(args.seed)
    loaded = load_world(args.scenario, options.overrides)
    rows = []
    for k in range(args.events):
        state = event(rng, doc, rooms, doors, plan_path)
        kinds = {"down": state.down, "remove": state.remove, "add": state.add, "door": state.doors}
        kind = next((k for k, v in kinds.items() if v), "state")
        t0 = time.perf_counter()
        budget = options if args.anytime_budget is None else options.but(time_budget=args.anytime_budget)
        try:  # as tmpnav.replan.Session.update: the scenario and its world loaded once, by the service
            report = replan(args.scenario, plan_path, state, budget, loaded=loaded)
            ok, left = "ok", len(report.revision.unreachable) if report.revision else 0
            steps = len(report.task.steps)
            value = round(objective_values(report).value, 3)
            resim = report.resimulated_cost  # the plan's cost as the planner saw it, against its re-simulation
            agree = abs(report.planner_cost - resim) / abs(resim) if resim else 0.0
        except TmpnavError as err:
            ok, left, steps, value, agree = f"error: {err}", 0, 0, float("nan"), float("nan")
        seconds = time.perf_counter() - t0
        rows.append({"event": k + 1, "time": state.time, "kind": kind, "seconds": round(seconds, 3), "result": ok,
                     "steps": steps, "unreachable": left, "objective": value,
                     "planner_vs_resimulated": agree})  # fmt: skip
        print(rows[-1], flush=True)
    with (args.output / f"{name}.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    secs = sorted(r["seconds"] for r in rows if r["result"] == "ok")
    p90 = secs[min(len(secs) - 1, int(0.9 * len(secs)))] if secs else float("nan")
    text = (
        f"{args.scenario}: first plan {first_s:.2f} s (cold cache); {len(rows)} events ({len(secs)} replanned)\n"
        f"replan latency: median {statistics.median(secs):.2f} s, p90 {p90:.2f} s, max {max(secs):.2f} s\n"
        f"planner's cost against the re-simulated one: largest relative difference "
        f"{max((r['planner_vs_resimulated'] for r in rows if r['result'] == 'ok'), default=float('nan')):.2e}\n"
        f"by kind: "
        + ", ".join(
            f"{k} {statistics.median([r['seconds'] for r in rows if r['kind'] == k and r['result'] == 'ok']):.2f} s"
            for k in KINDS
            if any(r["kind"] == k and r["result"] == "ok" for r in rows)
        )
        + f"\nmachine: {platform.processor() or platform.machine()}, python {platform.python_version()}\n"
        f"command: python benchmarks/bench_replan.py --scenario {args.scenario} --events {args.events} "
        f"--seed {args.seed}"
        + ("" if args.anytime_budget is None else f" --anytime-budget {args.anytime_budget:g}")
        + f" -o {args.output}\n"
    )
    (args.output / f"{name}.txt").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
