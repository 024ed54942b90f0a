"""The disturbance suite of the closed loop (issue 43): seeded event sets on shipped scenarios, each
executed by `tmpnav.replan.loop.closed_loop` (what `tmpnav simulate --events` runs) in its three
modes: closed loop, blind, knowing the events.

    python benchmarks/bench_disturb.py --scenario configs/building-4robots.yaml --sets 50 -o benchmarks/disturb

An event set has 1 to 3 events at random times within the first 70% of the plan's makespan, each
one of: a robot stopped for 10-40 s, a robot slowed to 0.3-0.7 of its speed for 20-60 s, a robot
down (never the last one up), the door of a goal room closed, a room added as a goal. Each set is
one session (its own noise seed). Writes `<name>.csv` (one row per set and mode) and `<name>.txt`:
the sets in which every goal still reachable was done, none twice, none lost; the closed loop's
executed makespan against the plan knowing the events (median ratio); the blind comparison; the
replans' latency.
"""

from __future__ import annotations

import argparse
import csv
import platform
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tmpnav.pipeline import PlanOptions, plan  # noqa: E402
from tmpnav.replan.events import Event, Events  # noqa: E402
from tmpnav.replan.loop import MODES, closed_loop  # noqa: E402
from tmpnav.results import PlanReport  # noqa: E402

KINDS = ("stop", "slow", "down", "close", "add")


def goal_doors(first: PlanReport) -> dict[str, str]:
    """Door -> the goal room it opens into (the room beside the door's midpoint)."""
    sc = first.scenario
    goals = set(sc.goals.all_rooms)
    out = {}
    for d in sc.doors:
        (x0, y0), (x1, y1) = d.segment
        mid = ((x0 + x1) / 2, (y0 + y1) / 2)
        for dx, dy in ((0, 0.3), (0, -0.3), (0.3, 0), (-0.3, 0)):
            room = first.world.room_of([mid[0] + dx, mid[1] + dy])
            if room is not None and room in goals:
                out[d.name] = room
                break
    return out


def event_set(rng: random.Random, first: PlanReport, doors: dict[str, str], source: Path) -> Events:
    """1 to 3 random events on the first plan (module docstring)."""
    sc = first.scenario
    robots = [r.name for r in sc.robots]
    span = first.schedule.makespan
    spare = [r.name for r in sc.rooms if r.name not in sc.goals.all_rooms]
    events: list[Event] = []
    down: list[str] = []
    for _ in range(rng.randint(1, 3)):
        at = round(rng.uniform(0.05, 0.7) * span, 1)
        kind = rng.choice(KINDS)
        robot = rng.choice([r for r in robots if r not in down])
        if kind == "down" and len(down) < len(robots) - 1:
            down.append(robot)
            events.append(Event(at, "down", robot))
        elif kind == "close" and doors:
            events.append(Event(at, "close", door=rng.choice(sorted(doors))))
        elif kind == "add" and spare:
            events.append(Event(at, "goals", add=(spare.pop(rng.randrange(len(spare))),)))
        elif kind == "slow":
            events.append(
                Event(at, "slow", robot, seconds=round(rng.uniform(20, 60), 1), factor=round(rng.uniform(0.3, 0.7), 2))
            )
        else:
            events.append(Event(at, "stop", robot, seconds=round(rng.uniform(10, 40), 1)))
    return Events(source, tuple(sorted(events, key=lambda e: e.at)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--sets", type=int, default=50)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-o", "--output", type=Path, required=True)
    args = ap.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    name = Path(args.scenario).stem
    cache = Path(tempfile.mkdtemp(prefix="tmpnav-disturb-bench-"))
    options = PlanOptions.of(cache_dir=cache)
    first = plan(args.scenario, options)
    doors = goal_doors(first)
    rng = random.Random(args.seed)
    rows = []
    latencies: list[float] = []
    ok_sets = 0
    ratios: list[float] = []
    blind_lost: list[int] = []
    t_all = time.perf_counter()
    for k in range(args.sets):
        events = event_set(rng, first, doors, Path(f"set-{k + 1}"))
        result = closed_loop(args.scenario, events, 1, args.seed * 1000 + k, options)
        runs = {m: result.runs[m][0] for m in MODES if result.runs[m]}
        loop = runs["closed loop"]
        latencies += [p.latency for p in loop.replans]
        fine = not loop.lost and not loop.twice
        ok_sets += fine
        if "knowing the events" in runs and runs["knowing the events"].makespan > 0:
            ratios.append(loop.makespan / runs["knowing the events"].makespan)
        blind_lost.append(len(runs["blind"].lost))
        for mode, r in runs.items():
            rows.append({
                "set": k + 1, "events": "; ".join(e.text() + f" at {e.at:g} s" for e in events.events), "mode": mode,
                "goals": len(r.goals), "done": len(r.done), "dropped": len(r.dropped), "lost": len(r.lost),
                "twice": len(r.twice), "makespan_s": round(r.makespan, 2), "cost": round(r.cost, 2),
                "wall_hit_steps": r.wall_hits, "contact_steps": r.contacts, "replans": len(r.replans),
                "latency_median_s": round(statistics.median([p.latency for p in r.replans]), 3) if r.replans else "",
                "failed_replans": sum(p.outcome.startswith("failed") for p in r.replans),
            })  # fmt: skip
        print(f"set {k + 1}: " + "; ".join(f"{e.text()} at {e.at:g} s" for e in events.events), flush=True)
        for mode, r in runs.items():
            print(f"  {mode}: done {len(r.done)}/{len(r.goals)} dropped {len(r.dropped)} lost {len(r.lost)} "
                  f"twice {len(r.twice)} makespan {r.makespan:.1f} s replans {len(r.replans)}", flush=True)  # fmt: skip
    with (args.output / f"{name}.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lat = sorted(latencies)
    text = (
        f"{args.scenario}: {args.sets} event sets (seed {args.seed}), one session each, "
        f"{time.perf_counter() - t_all:.0f} s in all\n"
        f"closed loop: every reachable goal done, none twice, none lost in {ok_sets}/{args.sets} sets\n"
        f"closed loop makespan / plan knowing the events: median {statistics.median(ratios):.3f} "
        f"(p90 {sorted(ratios)[min(len(ratios) - 1, int(0.9 * len(ratios)))]:.3f}, {len(ratios)} sets)\n"
        f"blind: goals lost {statistics.mean(blind_lost):.2f} per set on average, in "
        f"{sum(x > 0 for x in blind_lost)}/{args.sets} sets\n"
        + (
            f"replans: {len(lat)}, latency median {statistics.median(lat):.2f} s, "
            f"p90 {lat[min(len(lat) - 1, int(0.9 * len(lat)))]:.2f} s, max {lat[-1]:.2f} s\n"
            if lat
            else "replans: none\n"
        )
        + f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}\n"
        f"command: python benchmarks/bench_disturb.py --scenario {args.scenario} --sets {args.sets} "
        f"--seed {args.seed} -o {args.output}\n"
    )
    (args.output / f"{name}.txt").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
