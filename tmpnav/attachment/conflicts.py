"""Robots in each other's way: conflicts of a plan's schedule resolved by waits (then :mod:`tmpnav.attachment.passing`).

A plan's schedule (:mod:`tmpnav.attachment.clock`) moves every robot at once along the paths
the oracle chose for it, without looking at the other robots. Where two robots come closer
than their radii plus the margin of their uncertainty (:mod:`tmpnav.belief.conflicts`), one
of them must give way. :func:`resolve_conflicts` gives way by **waits only**: a move is held
back at its start, where its robot stands in the room or place its previous move ended in
(``TeamClock.run``'s ``delays``). Paths, goal choices and costs stay the oracle's, so the
beliefs stay those of the oracle's motions and the cost of the plan is still the cost of the
plan as executed: the resolved run *is* the re-simulation (with the same delays).

The method is conflict-based search (Sharon et al., "Conflict-based search for optimal
multi-agent pathfinding", AIJ 2015) over delays, seeded with prioritised planning's order
(Erdmann and Lozano-Perez 1987; with waits at places where a robot can stand aside, as in
Phillips and Likhachev's safe-interval path planning, ICRA 2011):

1. run the plan on the team's clock recording the beliefs, and check it with the independent
   checker; take the earliest conflict, between robots a and b over [t0, t1];
2. split it in two, as CBS does: either a gives way or b does. A robot gives way by holding
   back the move that puts it there -- the move it drives at t0, or, when it stands at t0,
   the move that brought it to where it stands -- until the other robot's conflicting
   interval has passed: the move then starts at t1 + dt;
3. the branch of the robot of lower priority is tried first: priority is the plan's order,
   so the robot whose move started later (the later plan step at a tie) yields, which is
   prioritised planning; the other branch is tried when that one cannot resolve it -- a
   robot standing for good (it has ended its plan) in the other's path cannot be waited
   out, so the move that brought it there is held back and the passer goes first. A robot
   that, held back, would stand where the other drives meanwhile gives way in vain (robots
   queued along one lane, the one in front held back): the other's branch goes first;
4. a wait changes the beliefs of everything after it (observations, goal choices), so every
   branch is run and checked again; depth first, until no conflict is left or after
   ``max_runs`` runs.

Why waits first: the roadmap paths are the oracle's, with beliefs and costs that the task
planner optimised; waits at the start of moves keep every motion as costed and only shift it in
time, so the search space is small (one delay per plan step) and each node is one run of the
clock. Conflicts no wait can resolve (two robots whose paths meet while one of them stands at
its start, two that swap rooms along one lane, partners of one paired move, robots that end
their plans closer than their margins) go on to :func:`tmpnav.attachment.passing.resolve_with_detours`: one robot drives
the move along another roadmap path around the others' runs (A* in space and time,
:mod:`tmpnav.attachment.detours`); the same moves, another motion, costed as executed.

:func:`tmpnav.attachment.passing.resolve_with_sidesteps` goes one step further where waits leave a conflict: beside the
detours, one robot of it makes its move through a siding, a room no goal names, so that the
other can pass (push-and-swap's move; Luna and Bekris, IJCAI 2011). That changes the plan and
its cost (the sidestep's motion is the oracle's, and costed as executed, but the task planner
did not choose it), so its :attr:`Resolution.plan` is the plan the delays belong to. Whatever
is left is returned in :attr:`Resolution.conflicts_left`, never hidden.

Use: ``res = resolve_with_sidesteps(carried, task.steps)`` (:mod:`tmpnav.attachment.passing`;
or :func:`resolve_conflicts` for waits only), then run ``res.plan`` with ``res.delays`` and ``res.detours``
(``CarriedCosts.replay``, ``resimulate``); ``res.run`` is that run already, recorded.
:func:`tmpnav.attachment.apart.keep_apart` applies it to a plan, as ``tmpnav plan`` does by
default. With a clock drift (:mod:`tmpnav.attachment.drift`) every check and every detour
keeps the pairs' time windows clear, not only the same planned instant.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun, Unreachable
from tmpnav.attachment.drift import clock_drift, trajectory_windows
from tmpnav.belief.conflicts import DEFAULT_DELTA, Conflict, find_conflicts, seen_std
from tmpnav.results import Schedule, TimedMove
from tmpnav.task.plans import Plan, Step

#: clock runs the search may make per plan (each is one run of the team's joint EKF)
MAX_RUNS = 40
#: times on the clock's grid agree to this (s)
EPS = 1e-6


@dataclass(frozen=True)
class Resolution:
    """The plan's waits: ``delays`` (plan step index -> seconds it is held back after it could
    start, for ``TeamClock.run`` and ``resimulate``), the run with them (trajectories
    recorded), the conflicts still in it, the conflicts of the plan as given (no waits), how
    many clock runs the search made, and the plan the delays belong to: the plan as given,
    or with sidesteps inserted (:func:`resolve_with_sidesteps`)."""

    delays: dict[int, float]
    run: ClockRun
    conflicts_left: list[Conflict]
    iterations: int
    conflicts_before: list[Conflict]
    plan: Plan
    detours: dict[tuple[int, str], tuple[int, ...]] = field(default_factory=dict)

    @property
    def resolved(self) -> bool:
        return not self.conflicts_left


@dataclass(frozen=True)
class _Node:
    delays: dict[int, float]
    run: ClockRun
    conflicts: list[Conflict]


def resolve_conflicts(
    costs: TeamClock | CarriedCosts,
    plan: Sequence[Step],
    radii: Mapping[str, float] | None = None,
    delta: float | None = None,
    max_runs: int = MAX_RUNS,
    detours: Mapping[tuple[int, str], tuple[int, ...]] | None = None,
    drift: float | None = None,
) -> Resolution:
    """Waits that keep the robots of ``plan`` out of each other's way (module docstring).
    ``radii``: robot -> radius (m), the scenario's by default; ``delta``: the risk threshold
    of the margin, the scenario's ``planner.max_risk`` when it has one, else 0.05;
    ``detours``: moves driven along other paths (``TeamClock.run``), kept in every run;
    ``drift``: how late a robot may run per second driven (the checker's time windows,
    tmpnav.attachment.drift), the scenario's by default.
    Raises Unreachable when the plan itself cannot be run."""
    detours = dict(detours or {})
    clock = costs.clock if isinstance(costs, CarriedCosts) else costs
    steps: Plan = tuple(plan)
    radii = dict(radii) if radii is not None else radii_of(clock)
    risk = delta if delta is not None else (clock.scenario.planner.max_risk or DEFAULT_DELTA)
    rate = drift if drift is not None else clock_drift(clock.scenario)
    apart_std = seen_std(clock.scenario.models)

    def check(delays: dict[int, float]) -> _Node:
        run = clock.run(steps, delays, record=True, detours=detours)
        assert run.trajectories is not None
        windows = trajectory_windows(run.trajectories, run.schedule, rate)
        return _Node(delays, run, find_conflicts(run.trajectories, radii, risk, windows, apart_std, run.tracks))

    root = check({})
    best, runs, longest = root, 1, root.run.makespan + clock.dt
    stack = [d for d in reversed(list(_branches(root, clock.dt, longest)))]
    seen = {_key(root.delays), *(_key(d) for d in stack)}
    while stack and best.conflicts and runs < max_runs:
        delays = stack.pop()
        runs += 1
        try:
            node = check(delays)
        except Unreachable:  # a wait changed a belief so much that a goal cannot be reached
            continue
        if _better(node, best):
            best = node
        for child in reversed(list(_branches(node, clock.dt, longest))):
            if _key(child) not in seen:
                seen.add(_key(child))
                stack.append(child)
    return Resolution(best.delays, best.run, best.conflicts, runs, root.conflicts, steps, detours)


def radii_of(clock: TeamClock) -> dict[str, float]:
    """Robot -> radius (m), the scenario's."""
    return {r: clock.scenario.robot(r).radius for r in clock.start.names}


def _key(delays: Mapping[int, float]) -> tuple[tuple[int, float], ...]:
    return tuple(sorted((k, round(v, 6)) for k, v in delays.items() if v > EPS))


def _better(node: _Node, best: _Node) -> bool:
    """Fewer conflicts left, then the shorter makespan."""
    return (len(node.conflicts), node.run.makespan) < (len(best.conflicts), best.run.makespan)


def _branches(node: _Node, dt: float, longest: float) -> Iterator[dict[int, float]]:
    """CBS's split of the node's earliest conflict: the delays with one robot giving way, the
    robot of lower priority first; none for a robot that cannot give way, or whose wait would
    be pointless or longer than ``longest``."""
    if not node.conflicts:
        return
    conflict, schedule = node.conflicts[0], node.run.schedule
    a, b = conflict.robots
    options = [(held_move(schedule, a, conflict.t_from), a), (held_move(schedule, b, conflict.t_from), b)]
    options.sort(key=lambda o: (o[0].start, o[0].step) if o[0] is not None else (-1.0, -1), reverse=True)
    waits = []
    for move, robot in options:
        other = b if robot == a else a
        if move is None or _pointless(schedule, move, other, conflict.t_from):
            continue
        wait = node.delays.get(move.step, 0.0) + conflict.t_to + conflict.window + dt - move.start
        if wait <= longest:
            until = conflict.t_to + conflict.window + dt  # when the move would start
            waits.append((_stands_in_way(node.run, move, other, until, conflict.required_separation, dt), move, wait))
    # a robot held back where the other then drives through gives way in vain: the other first
    waits.sort(key=lambda w: w[0])  # (stable: otherwise the robot of lower priority first)
    for _, move, wait in waits:
        yield {**node.delays, move.step: round(wait / dt) * dt}


def _stands_in_way(run: ClockRun, move: TimedMove, other: str, until: float, separation: float, dt: float) -> bool:
    """Whether ``move``'s robot, held back until ``until`` (s) where the move starts, would stand
    where ``other`` drives meanwhile (closer than ``separation``), as ``other`` drives in ``run``:
    robots queued along one lane, the one in front held back, the one behind driving through it."""
    tracks = run.tracks
    if tracks is None or move.robot not in tracks or other not in tracks:
        return False
    here, there = tracks[move.robot][0], tracks[other][0]
    if not len(here) or not len(there):
        return False
    lo, hi = round(move.start / dt), round(until / dt)
    stand = here[min(lo, len(here) - 1)]
    path = there[min(lo, len(there) - 1) : min(hi, len(there) - 1) + 1]
    return bool(len(path)) and float(np.min(np.hypot(*(path - stand).T))) < separation


def held_move(schedule: Schedule, robot: str, t: float) -> TimedMove | None:
    """The move that puts ``robot`` where it is at ``t``: the one it drives then, else the one
    that brought it to where it stands; None while it stands at its start."""
    timeline = schedule.timeline(robot)
    driving = next((m for m in timeline if m.start - EPS <= t < m.end - EPS), None)
    if driving is not None:
        return driving
    return next((m for m in reversed(timeline) if m.end - EPS <= t), None)


def _pointless(schedule: Schedule, move: TimedMove, other: str, t: float) -> bool:
    """Whether holding ``move`` back cannot take its robot out of ``other``'s way: the other
    robot makes the same (paired) move, or stands at ``t`` where it will stand for good (it
    has ended its plan), so the robot would meet it there whenever it came."""
    timeline = schedule.timeline(other)
    return any(m.step == move.step for m in timeline) or all(m.end - EPS <= t for m in timeline)
