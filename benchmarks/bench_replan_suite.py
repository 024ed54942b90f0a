"""Seeded replans of a shift (issue 56, "replans correct by construction"): each seed draws a team
state part-way through the shift's plan and replans it in the process, as ``tmpnav replan`` does.

    python benchmarks/bench_replan_suite.py --scenario benchmarks/shift/warehouse-far-dock.yaml \
        --seeds 50 -o benchmarks/replan_suite

A state (seed k, :func:`draw`) is the team at a time t drawn in 5-85% of the plan's makespan, each
robot where the plan has it with the plan's covariance; then, each with its own chance:
- one robot down (half the seeds);
- the robot that is at a station at t keeps serving (every seed where one is), or its service is
  cut short (``interrupted``, a quarter of those);
- one or two goals added with job fields: a service of 10-30 s, and half of them a window that
  opens and closes on the shift's clock (half the seeds);
- one goal not yet done removed (a fifth of the seeds).

Each revision is checked, each check its own column of ``<name>.csv``:
- ``goals``: every goal left (the shift's and the added, less those removed and done) is done:
  entered by a move (a station's service given once), or a robot stands in it (and serves it
  there when its job asks a service), or it is named out of reach with a reason a user can check
  (only robots that are down may serve it); every robot that is not down ends at its end; no goal
  done before is served again. A robot may drive through a room on its way (a belief-space plan
  may re-localise there): that is no visit;
- ``windows``: every move into a room with a window arrives within it, on the shift's clock
  (the revision's start time plus its arrival);
- ``services``: the robot at a station keeps it for the rest of its service (``held``), and starts
  its next move no earlier; one whose service was cut short is not held and its station is left
  to do;
- ``answer``: a plan, or "no plan" (recorded with its message: each is then a case for an
  exhaustive check; none is expected while the rest of the old plan can be repaired).
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import random
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tmpnav import pipeline  # noqa: E402
from tmpnav.errors import TmpnavError  # noqa: E402
from tmpnav.replan import replan  # noqa: E402
from tmpnav.replan.state import RobotState, TeamState  # noqa: E402
from tmpnav.report.plan_json import plan_document  # noqa: E402
from tmpnav.results import PlanReport  # noqa: E402
from tmpnav.types import Job  # noqa: E402

#: s: an arrival may pass a window's latest (or come before its earliest) by this much (rounding)
TOL = 1e-6


def at_station(plan: PlanReport, t: float) -> tuple[str, str, float] | None:
    """(robot, room, service left) of the first robot serving a job at ``t``, if any."""
    for m in plan.schedule.moves:
        begins = m.end + m.opens
        if m.service > 0 and begins <= t < begins + m.service:
            return m.robot, m.target, begins + m.service - t
    return None


def draw(rng: random.Random, plan: PlanReport, source: Path) -> tuple[TeamState, dict[str, Any]]:
    """The team's state of one seed, and what was drawn (the module docstring)."""
    scenario = plan.scenario
    t = round(rng.uniform(0.05, 0.85) * plan.schedule.makespan, 1)
    names = [r.name for r in scenario.robots]
    serving = at_station(plan, t)
    down = rng.choice(names) if rng.random() < 0.5 else None
    if serving is not None and down == serving[0]:
        down = None
    interrupted = serving is not None and rng.random() < 0.25
    robots: dict[str, RobotState] = {}
    for name in names:
        if name == down:
            robots[name] = RobotState(name, down=True)
            continue
        steps = plan.trajectories[name]
        step = min(steps, key=lambda s: abs(s.t - t))
        cut = interrupted and serving is not None and serving[0] == name
        robots[name] = RobotState(name, tuple(step.mean), tuple(tuple(r) for r in step.cov), interrupted=cut)
    goals = scenario.goals
    taken = set(goals.all_rooms) | {x for _, x in goals.ends}
    free = [r.name for r in scenario.rooms if r.name not in taken]
    add: list[str] = []
    jobs: list[Job] = []
    if free and rng.random() < 0.5:
        for room in rng.sample(free, min(len(free), rng.choice((1, 2)))):
            window = None
            if rng.random() < 0.5:
                opens = round(t + rng.uniform(0, 120), 1)
                window = (opens, round(opens + rng.uniform(300, 900), 1))
            add.append(room)
            jobs.append(Job(room, float(rng.choice((10, 20, 30))), window=window))
    remove: tuple[str, ...] = ()
    entered = {m.target for m in plan.schedule.moves if m.end <= t}
    left = [x for x in goals.all_rooms if x not in entered and x not in add]
    if left and rng.random() < 0.2:
        remove = (rng.choice(left),)
    state = TeamState(source, t, robots, None, {}, tuple(add), remove, tuple(jobs))
    drawn = {
        "time": t,
        "down": down,
        "serving": None if serving is None else f"{serving[0]}@{serving[1]}+{serving[2]:.1f}s",
        "interrupted": interrupted,
        "added": " ".join(add),
        "added_windows": sum(j.window is not None for j in jobs),
        "removed": " ".join(remove),
    }
    return state, drawn


def check(first: PlanReport, state: TeamState, rev: PlanReport) -> dict[str, str]:
    """The checks of the module docstring, each "ok" or what failed."""
    assert rev.revision is not None
    r = rev.revision
    out = {"goals": "ok", "windows": "ok", "services": "ok"}
    goals = first.scenario.goals
    dropped_ends = {x for robot, x in goals.ends if robot in r.down}  # a robot down: its end is dropped
    wanted = [x for x in (*goals.all_rooms, *state.add) if x not in state.remove and x not in dropped_ends]
    unreachable = {room for room, _ in r.unreachable}
    entered: dict[str, int] = {}
    served: dict[str, int] = {}
    for m in rev.schedule.moves:
        entered[m.target] = entered.get(m.target, 0) + 1
        served[m.target] = served.get(m.target, 0) + int(m.service > 0)
    last = {robot: moves[-1].target for robot in rev.table.robots if (moves := rev.schedule.timeline(robot))}
    ends = {x: robot for robot, x in goals.ends if robot not in r.down}
    held_rooms = {room for _, room, _ in r.held}
    starts = set(rev.table.start_location.values())
    serving = at_station(first, state.time)
    cut_short = set()
    if serving is not None and serving[0] in state.robots and state.robots[serving[0]].interrupted:
        cut_short.add(serving[1])
    problems = []
    for x in dict.fromkeys(wanted):
        job = next((j for j in (*state.jobs, *goals.jobs) if j.room == x), None)
        service = job is not None and job.service > 0
        if x in ends:  # a robot's end: its last move enters it (another robot may pass through)
            robot = ends[x]
            if last.get(robot, rev.table.start_location.get(robot)) != x:
                problems.append(f"{robot} does not end at {x}")
            continue
        if x in r.done:
            if served.get(x):
                problems.append(f"{x} done and served again")
            continue
        if x in unreachable:
            if job is None or not job.robots or not set(job.robots) <= set(r.down):
                problems.append(f"{x} named out of reach ({dict(r.unreachable)[x]})")
            continue
        if x in held_rooms or (x in starts and not entered.get(x)):
            # a robot is at it finishing its service, or stands in it: done (docs/replan.md)
            if service and x not in held_rooms and x not in cut_short:
                problems.append(f"{x} done by a robot standing in it, its {job.service:g} s service never done")
            continue
        if not entered.get(x):
            problems.append(f"{x} not done")
        elif service and served.get(x, 0) != 1:
            problems.append(f"{x} served {served.get(x, 0)} times")
    if problems:
        out["goals"] = "; ".join(problems)
    windows = {j.room: j.window for j in (*goals.jobs, *state.jobs) if j.window is not None}
    late = []
    for m in rev.schedule.moves:
        w = windows.get(m.target)
        if w is None:
            continue
        arrival = r.start_time + m.end
        if arrival > w[1] + TOL or r.start_time + m.end + m.opens < w[0] - TOL:
            late.append(f"{m.robot} at {m.target} {arrival:.1f} s, window [{w[0]:g}, {w[1]:g}]")
    if late:
        out["windows"] = "; ".join(late)
    if serving is not None:
        robot, room, left = serving
        cut = state.robots[robot].interrupted if robot in state.robots else False
        held = {rb: (rm, s) for rb, rm, s in r.held}
        first_move = next((m for m in rev.schedule.moves if m.robot == robot), None)
        if cut:
            if robot in held:
                out["services"] = f"{robot} held at {room} though its service was cut short"
            elif room in r.done and room not in starts:
                out["services"] = f"{room} counted done though {robot}'s service was cut short and it left"
        elif robot not in r.down:
            if robot not in held or abs(held[robot][1] - left) > first.scenario.models.dt + TOL:
                out["services"] = f"{robot} not held at {room} for the {left:.1f} s of service left ({held.get(robot)})"
            elif first_move is not None and first_move.start < held[robot][1] - TOL:
                out["services"] = f"{robot} leaves {room} at {first_move.start:.1f} s, before its service ends"
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default=str(ROOT / "benchmarks/shift/warehouse-far-dock.yaml"))
    parser.add_argument("--seeds", type=int, default=50)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("-o", "--output", type=Path, required=True)
    args = parser.parse_args()
    path = Path(args.scenario)
    options = pipeline.PlanOptions.of()
    loaded = pipeline.load_world(path, options.overrides)
    first = pipeline.plan(path, options, loaded=loaded)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        plan_path = Path(tmp) / "plan.json"
        plan_path.write_text(json.dumps(plan_document(first)))
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            state, drawn = draw(random.Random(seed), first, Path(tmp) / f"state-{seed}.yaml")
            began, cpu = time.perf_counter(), time.process_time()
            row: dict[str, Any] = {"seed": seed, **drawn}
            try:
                rev = replan(path, plan_path, state, options, loaded)
            except TmpnavError as err:
                row.update(answer=f"no plan: {err}", goals="", windows="", services="")
            else:
                assert rev.revision is not None
                row.update(answer=f"plan ({rev.revision.rule})", **check(first, state, rev))
            row.update(wall_s=round(time.perf_counter() - began, 2), cpu_s=round(time.process_time() - cpu, 2))
            rows.append(row)
            print(row, flush=True)
    args.output.mkdir(parents=True, exist_ok=True)
    name = path.stem
    with (args.output / f"{name}.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    ok = {c: sum(r[c] == "ok" for r in rows) for c in ("goals", "windows", "services")}
    planned = sum(r["answer"].startswith("plan") for r in rows)
    lines = [
        f"{name}: {len(rows)} seeded replans ({platform.node()}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())})",
        f"  a plan: {planned}/{len(rows)} ({sum('repair' in r['answer'] for r in rows)} by repair); "
        f"no plan: {len(rows) - planned}",
        f"  goals left each done once: {ok['goals']}/{planned}; windows held on the shift's clock: "
        f"{ok['windows']}/{planned}; services completed: {ok['services']}/{planned}",
        f"  drawn: {sum(bool(r['down']) for r in rows)} with a robot down, "
        f"{sum(bool(r['serving']) for r in rows)} with a robot at a station "
        f"({sum(bool(r['interrupted']) for r in rows)} cut short), {sum(bool(r['added']) for r in rows)} with goals "
        f"added ({sum(r['added_windows'] for r in rows)} windows), "
        f"{sum(bool(r['removed']) for r in rows)} with one removed",
        f"  replan time in the process: median {sorted(r['wall_s'] for r in rows)[len(rows) // 2]:.1f} s wall, "
        f"{sorted(r['cpu_s'] for r in rows)[len(rows) // 2]:.1f} s CPU of this process (the oracle's workers apart)",
    ]
    failed = [r for r in rows if r["answer"].startswith("no plan") or any(r[c] not in ("ok", "") for c in ok)]
    lines += [f"  seed {r['seed']}: {r['answer']}; {r['goals']}; {r['windows']}; {r['services']}" for r in failed]
    (args.output / f"{name}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
