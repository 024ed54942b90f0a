"""What the closed loop of ``tmpnav simulate --events`` reports (:mod:`tmpnav.replan.loop`):
each session's runs in the three modes, its replans, and the summary, loop.csv, replans.csv and
loop.json made of them."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tmpnav.replan.events import Events
from tmpnav.results import PlanReport

#: the three ways each session is executed
#: the three ways each session is executed
MODES = ("closed loop", "blind", "knowing the events")


@dataclass(frozen=True)
class Replan:
    """One replan of a session: when, why, how long it took, what came of it."""

    session: int
    time: float  # s on the team's clock
    reason: str
    latency: float  # s of wall-clock time
    outcome: str  # "planned", "nothing left", or "failed: <why>"
    unreachable: tuple[str, ...] = ()


@dataclass
class Run:
    """One session executed one way (:data:`MODES`)."""

    mode: str
    session: int
    goals: tuple[str, ...]  # the goal rooms to do: the scenario's, added, not removed
    done: tuple[str, ...]  # goal rooms a move ended in, in order
    twice: tuple[str, ...]  # goal rooms more than one move ended in
    dropped: tuple[str, ...]  # goals the replans named as out of reach, or a down robot's end
    makespan: float  # s: when the last robot was done
    cost: float  # M_u c_u + M_G c_G + M_Sigma c_Sigma as executed (docs/models.md)
    wall_hits: int  # control steps with a true pose in a wall (all robots)
    contacts: int  # control steps with two robots touching
    replans: list[Replan] = field(default_factory=list)

    @property
    def lost(self) -> tuple[str, ...]:
        """Goals neither done nor dropped."""
        return tuple(x for x in self.goals if x not in self.done and x not in self.dropped)


@dataclass
class LoopResult:
    """Every session in the three modes, and the plans they started from."""

    events: Events
    planned: PlanReport  # the first plan
    informed: PlanReport | None  # the plan knowing the events (None when it could not be made)
    informed_error: str
    runs: dict[str, list[Run]]
    server: str | None = None  # the URL of the tmpnav serve the closed loop's plans came from


def summary(result: LoopResult) -> list[str]:
    """What ``tmpnav simulate --events`` prints: the replans, the goals, the makespan and cost of
    the three modes."""
    closed = result.runs["closed loop"]
    n = len(closed)
    events = result.events
    lines = [
        f"closed loop: {n} session(s) with {len(events.events)} event(s) from {events.source.name} "
        f"(replanning at each change of the problem and when a robot is {events.late:g} s late)"
        + (f"; its plans from tmpnav serve at {result.server}" if result.server else "")
    ]
    replans = [p for r in closed for p in r.replans]
    if replans:
        latencies = np.array([p.latency for p in replans])
        failed = sum(p.outcome.startswith("failed") for p in replans)
        lines.append(
            f"  replans: {len(replans)} ({len(replans) / n:.1f} per session), latency median "
            f"{np.median(latencies):.2f} s, max {latencies.max():.2f} s" + (f"; {failed} failed" if failed else "")
        )
        reasons: dict[str, int] = {}
        for p in replans:
            for why in p.reason.split("; "):
                key = "lateness" if why.startswith("late by") else why
                reasons[key] = reasons.get(key, 0) + 1
        lines.append("  reasons: " + ", ".join(f"{k} {v}" for k, v in reasons.items()))
    else:
        lines.append("  replans: none")
    for mode in MODES:
        runs = result.runs[mode]
        if not runs:
            lines.append(f"  {mode}: no plan ({result.informed_error})")
            continue
        lines.append("  " + _mode_line(mode, runs))
    return lines


def _mode_line(mode: str, runs: list[Run]) -> str:
    goals = np.mean([len(r.goals) for r in runs])
    done = np.mean([len(r.done) for r in runs])
    dropped = np.mean([len(r.dropped) for r in runs])
    lost = np.mean([len(r.lost) for r in runs])
    twice = sum(len(r.twice) for r in runs)
    spans = np.array([r.makespan for r in runs])
    costs = np.array([r.cost for r in runs])
    walls = sum(r.wall_hits > 0 for r in runs)
    touch = sum(r.contacts > 0 for r in runs)
    return (
        f"{mode}: goals done {done:.1f} of {goals:.1f}, dropped {dropped:.1f}, lost {lost:.1f}, twice {twice}; "
        f"makespan median {np.median(spans):.1f} s; cost median {np.median(costs):.1f}; "
        f"executions with a wall hit {walls}/{len(runs)}, with a contact {touch}/{len(runs)}"
    )


def runs_csv(result: LoopResult) -> str:
    """One row per session and mode (loop.csv)."""
    rows = ["mode,session,goals,done,dropped,lost,twice,makespan_s,cost,wall_hit_steps,contact_steps,replans"]
    for mode in MODES:
        for r in result.runs[mode]:
            rows.append(
                f"{mode},{r.session + 1},{len(r.goals)},{len(r.done)},{len(r.dropped)},{len(r.lost)},{len(r.twice)},"
                f"{r.makespan:.6g},{r.cost:.6g},{r.wall_hits},{r.contacts},{len(r.replans)}"
            )
    return "\n".join(rows) + "\n"


def replans_csv(result: LoopResult) -> str:
    """One row per replan of the closed loop (replans.csv)."""
    rows = ["session,time_s,reason,latency_s,outcome,unreachable"]
    for r in result.runs["closed loop"]:
        for p in r.replans:
            rows.append(
                f"{p.session + 1},{p.time:.6g},{_quoted(p.reason)},{p.latency:.4f},{_quoted(p.outcome)},"
                f"{' '.join(p.unreachable)}"
            )
    return "\n".join(rows) + "\n"


def _quoted(text: str) -> str:
    return '"' + text.replace('"', '""') + '"'


def document(result: LoopResult) -> dict[str, Any]:
    """The closed loop's results as JSON data (loop.json)."""
    return {
        "events": str(result.events.source),
        "server": result.server,
        "late_s": result.events.late,
        "planned_makespan_s": result.planned.schedule.makespan,
        "informed_makespan_s": result.informed.schedule.makespan if result.informed is not None else None,
        "runs": [
            {
                "mode": r.mode,
                "session": r.session + 1,
                "goals": list(r.goals),
                "done": list(r.done),
                "twice": list(r.twice),
                "dropped": list(r.dropped),
                "lost": list(r.lost),
                "makespan_s": r.makespan,
                "cost": r.cost,
                "wall_hit_steps": r.wall_hits,
                "contact_steps": r.contacts,
                "replans": [
                    {
                        "time_s": p.time,
                        "reason": p.reason,
                        "latency_s": p.latency,
                        "outcome": p.outcome,
                        "unreachable": list(p.unreachable),
                    }
                    for p in r.replans
                ],
            }
            for mode in MODES
            for r in result.runs[mode]
        ],
    }
