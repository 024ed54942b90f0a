"""Past what waits leave: detours and sidesteps (:mod:`tmpnav.attachment.conflicts` has the waits).

Conflicts no wait can resolve (two robots whose paths meet while one of them stands at its
start, two that swap rooms along one lane, partners of one paired move, robots that end their
plans closer than their margins) go on to :func:`resolve_with_detours`: one robot drives the
move along another roadmap path around the others' runs (A* in space and time,
:mod:`tmpnav.attachment.detours`); the same moves, another motion, costed as executed.

:func:`resolve_with_sidesteps` goes one step further: beside the detours, one robot of the
conflict makes its move through a siding, a room no goal names, so that the other can pass
(push-and-swap's move; Luna and Bekris, IJCAI 2011). That changes the plan and its cost (the
sidestep's motion is the oracle's, and costed as executed, but the task planner did not choose
it), so its :attr:`Resolution.plan` is the plan the delays belong to. Whatever is left is
returned in :attr:`Resolution.conflicts_left`, never hidden.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import replace

import numpy as np

from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import Unreachable
from tmpnav.attachment.conflicts import EPS, MAX_RUNS, Resolution, held_move, radii_of, resolve_conflicts
from tmpnav.attachment.detours import REACH, Drive, Obstacle, detour, near_nodes
from tmpnav.attachment.drift import clock_drift, trajectory_windows
from tmpnav.belief.conflicts import DEFAULT_DELTA, Conflict, margin_factor, seen_std, separation_std
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.table import start_location
from tmpnav.results import Schedule, TimedMove
from tmpnav.roadmap.graph import segment_margins
from tmpnav.task.objectives import OBJECTIVES
from tmpnav.task.plans import Plan, Step

#: siding rooms tried per robot of a conflict that waits cannot resolve
SIDINGS = 3
#: rounds of detours per plan, each for the first conflict left
DETOUR_ROUNDS = 3
#: a detour keeps this much more than the required separation (m), and takes the detouring
#: robot's uncertainty as DETOUR_SIGMA times the largest it had on the move it replaces
DETOUR_MARGIN = 0.05
DETOUR_SIGMA = 1.1


# ---------------------------------------------------------------------- detours


def resolve_with_detours(
    costs: TeamClock | CarriedCosts,
    res: Resolution,
    radii: Mapping[str, float] | None = None,
    delta: float | None = None,
    max_runs: int = MAX_RUNS,
    rounds: int = DETOUR_ROUNDS,
    drift: float | None = None,
) -> Resolution:
    """``res`` (a plan's waits), and where they leave a conflict, **detours**: a robot of the
    first conflict left drives the move it makes then along another roadmap path, found by
    A* in space and time around every other robot's run (:mod:`tmpnav.attachment.detours`;
    the robot of lower priority first, then the other), and waits are searched again with
    it. The plan stays the same (the same moves, the same goal instantiations); the detour's
    motion, beliefs and cost are the clock's, as executed. Of the detoured resolutions the
    one with the fewest conflicts left and then the least objective is kept, and its first
    conflict left gets the same treatment, up to ``rounds`` times. The detours keep clear of
    the other robots within the pairs' time windows of ``drift`` (the scenario's by default),
    as the checker asks."""
    clock = costs.clock if isinstance(costs, CarriedCosts) else costs
    radii = dict(radii) if radii is not None else radii_of(clock)
    risk = delta if delta is not None else (clock.scenario.planner.max_risk or DEFAULT_DELTA)
    rate = drift if drift is not None else clock_drift(clock.scenario)
    rank = _ranker(clock)
    best, runs = res, res.iterations
    for _ in range(rounds):
        if not best.conflicts_left:
            break
        tries = ((best.plan, detours) for detours in _detoured(clock, best, radii, risk, rate))
        better, spent = _next_best(costs, best, tries, rank, radii, delta, max_runs, drift=rate)
        runs += spent
        if better is None:
            break
        best = better
    return replace(best, iterations=runs, conflicts_before=res.conflicts_before)


def _next_best(
    costs: TeamClock | CarriedCosts,
    best: Resolution,
    tries: Iterable[tuple[Plan, Mapping[tuple[int, str], tuple[int, ...]] | None]],
    rank: Callable[[Resolution], tuple[int, float]],
    radii: Mapping[str, float] | None,
    delta: float | None,
    max_runs: int,
    budget: int | None = None,
    drift: float | None = None,
) -> tuple[Resolution | None, int]:
    """Each (plan, detours) of ``tries`` with its waits searched; the best of them by ``rank`` if
    it leaves fewer conflicts than ``best`` (else None), and the clock runs made. No try starts
    once ``budget`` runs are made."""
    found, runs = [], 0
    for plan, detours in tries:
        if budget is not None and runs >= budget:
            break
        try:
            found.append(resolve_conflicts(costs, plan, radii, delta, max_runs, detours, drift))
        except Unreachable:  # a wait changed a belief so much that a goal cannot be reached
            continue
        runs += found[-1].iterations
    better = min(found, key=rank, default=None)
    if better is None or rank(better)[0] >= len(best.conflicts_left):
        return None, runs
    return better, runs


def _detoured(
    clock: TeamClock, res: Resolution, radii: Mapping[str, float], risk: float, drift: float
) -> Iterator[dict[tuple[int, str], tuple[int, ...]]]:
    """The resolution's detours with one more: the move a robot of the first conflict left
    drives when it begins, around the other robots as they ran (their centres at every step,
    the separation the conflict rule asks with this robot's largest uncertainty on the move,
    times DETOUR_SIGMA, plus DETOUR_MARGIN, within the pair's time window of ``drift``)."""
    conflict, run, names = res.conflicts_left[0], res.run, clock.start.names
    trajectories = run.trajectories
    assert trajectories is not None
    seen = seen_std(clock.scenario.models)
    t = round(conflict.t_from / clock.dt)
    k = margin_factor(risk)
    windows = trajectory_windows(trajectories, run.schedule, drift)
    driving = [m for m in run.moves if names[m.robot] in conflict.robots and m.start <= t < m.end]
    for move in sorted(driving, key=lambda m: (m.start, m.step), reverse=True):
        robot = names[move.robot]
        own = trajectories[robot][move.start : move.end + 1]
        sigma = DETOUR_SIGMA * separation_std(own, seen).max()
        obstacles = []
        for other in names:
            if other == robot or len(trajectories[other]) <= move.start:
                continue
            window = _steps(windows.get((min(robot, other), max(robot, other))), clock.dt)
            t0 = max(0, move.start - int(window[move.start :].max(initial=0)))  # within its window before
            steps = trajectories[other][t0:]
            xy = np.array([s.mean[:2] for s in steps], dtype=float)
            others = separation_std(steps, seen)
            need = radii[robot] + radii[other] + k * (sigma + others) + DETOUR_MARGIN
            obstacles.append(Obstacle(t0, xy, need, _rows(window, t0, len(steps))))
        spec = clock.scenario.robot(robot)
        path = detour(
            clock.lib.roadmap,
            move.motion.path,
            float(move.motion.poses[0, 2]),
            move.start,
            Drive(spec.speed, spec.turn_rate, clock.dt),
            obstacles,
            move.motion.n_steps,
            edges=_as_clear(clock.lib, move.motion.path, spec.radius),
        )
        if path is not None and path != tuple(move.motion.path):
            yield {**res.detours, (move.step, robot): path}


def _steps(window: np.ndarray | None, dt: float) -> np.ndarray:
    """A time window (s per step; None: 0) in whole control steps."""
    if window is None:
        return np.zeros(1, dtype=np.int64)
    return np.floor(np.asarray(window) / dt + EPS).astype(np.int64)


def _rows(window: np.ndarray, t0: int, rows: int) -> np.ndarray:
    """The window (control steps) at each of ``rows`` steps from ``t0`` (the last held)."""
    at = np.minimum(np.arange(t0, t0 + rows), window.shape[0] - 1)
    return window[at]


def _as_clear(lib: MotionLibrary, path: Sequence[int], radius: float) -> np.ndarray:
    """The roadmap edges a detour of ``path`` may use: those near it (within the search's
    REACH) whose footprint clears the walls (margin at least 0), or is at least as clear as the
    tightest segment of ``path``. A stricter rule (as clear as ``path`` everywhere) leaves the
    paper's swap without a detour: its door frames are 0.18 m from the planned path and 0.04 m
    from the lane that passes."""
    nodes, edges = lib.roadmap.nodes, lib.roadmap.edges
    points = nodes[list(path)]
    tightest = float(segment_margins(points[:-1], points[1:], lib.world, radius).min(initial=np.inf))
    near = near_nodes(nodes, points, REACH)
    candidates = near[edges[:, 0]] & near[edges[:, 1]]
    ok = np.zeros(edges.shape[0], dtype=bool)
    a, b = nodes[edges[candidates, 0]], nodes[edges[candidates, 1]]
    ok[candidates] = segment_margins(a, b, lib.world, radius) >= min(tightest, 0.0) - 1e-9
    return ok


def _ranker(clock: TeamClock) -> Callable[[Resolution], tuple[int, float]]:
    """Resolutions ranked by the conflicts they leave, then the scenario's objective of their
    run (a move over the chance constraint costs more than any plan within it)."""
    objective = OBJECTIVES[clock.scenario.planner.objective]

    def rank(res: Resolution) -> tuple[int, float]:
        cost = sum(res.run.step_costs(len(res.plan), clock.scenario.cost, clock.scenario.planner.max_risk))
        return len(res.conflicts_left), objective.value(cost, res.run.makespan, clock.scenario.cost)

    return rank


# ---------------------------------------------------------------------- sidesteps


def resolve_with_sidesteps(
    costs: TeamClock | CarriedCosts,
    plan: Sequence[Step],
    radii: Mapping[str, float] | None = None,
    delta: float | None = None,
    max_runs: int = MAX_RUNS,
    sidings: int = SIDINGS,
    detours: bool = True,
    budget: int | None = None,
    drift: float | None = None,
) -> Resolution:
    """:func:`resolve_conflicts`; where waits leave a conflict, :func:`resolve_with_detours`,
    and apart from it a **sidestep**: one robot
    of the conflict makes its move in two, through a room that no goal names (a siding near
    where they met), so that the other can pass while it stands there; waits are then
    searched again on that plan. This is push-and-swap's move (Luna and Bekris, IJCAI 2011):
    two robots that must swap along one lane cannot pass by waiting, only by one stepping
    aside. It changes the plan (``Resolution.plan``): the sidestep's motion costs more than
    the move it replaces, and the task planner did not choose it. Up to ``sidings`` rooms are
    tried per robot, nearest to where they met; of the plans with the fewest conflicts left,
    the one of least objective (the scenario's: cost, weighted or makespan) is kept, and its
    first conflict left, if any, gets the same treatment. Of the detoured and the sidestepped
    resolution, the one with the fewer conflicts left and then the least objective is
    returned. ``detours=False``: waits and sidesteps only; ``sidings=0``: of the sidesteps,
    only paired moves split in two; ``budget``: no sidestep is tried once the search has made
    that many clock runs in all; ``drift``: the checker's time windows (the scenario's by
    default, tmpnav.attachment.drift)."""
    waits = resolve_conflicts(costs, plan, radii, delta, max_runs, drift=drift)
    if waits.resolved:
        return waits
    clock = costs.clock if isinstance(costs, CarriedCosts) else costs
    rank = _ranker(clock)
    detoured = resolve_with_detours(costs, waits, radii, delta, max_runs, drift=drift) if detours else waits
    best, runs = waits, detoured.iterations
    tried: set[Plan] = {best.plan}

    def untried(res: Resolution) -> Iterator[tuple[Plan, None]]:
        for candidate in _sidestepped(clock, res, sidings):
            if candidate not in tried:
                tried.add(candidate)
                yield candidate, None

    while best.conflicts_left:
        left = None if budget is None else budget - runs
        better, spent = _next_best(costs, best, untried(best), rank, radii, delta, max_runs, left, drift)
        runs += spent
        if better is None:
            break
        best = better
    best = min((detoured, best), key=rank)  # a tie goes to the detour: it keeps the plan's steps
    return replace(best, iterations=runs, conflicts_before=waits.conflicts_before)


def _sidestepped(clock: TeamClock, res: Resolution, sidings: int) -> Iterator[Plan]:
    """Plans with one robot of the first conflict left making the move that puts it there
    through a siding room, the robot of lower priority first; a paired move is also split in
    two single moves, the other robot's first (its robot of lower priority then waits)."""
    conflict, schedule, plan = res.conflicts_left[0], res.run.schedule, res.plan
    moves = [held_move(schedule, r, conflict.t_from) or _first(schedule, r) for r in conflict.robots]
    idle = [r for r, m in zip(conflict.robots, moves, strict=True) if m is None]
    yield from _parked_aside(clock, plan, conflict, idle, sidings)
    for move in sorted((m for m in moves if m is not None), key=lambda m: (m.start, m.step), reverse=True):
        step = plan[move.step]
        # a paired move is made as two single moves (so that one may wait for the other), or
        # with the robot of the conflict's through a siding
        mine = next(m for m in step if m[0] == move.robot)
        others = tuple((m,) for m in step if m is not mine)
        if others:
            yield (*plan[: move.step], *others, (mine,), *plan[move.step + 1 :])
        robot, origin, target = mine
        for room in _sidings(clock, conflict, {origin, target}, sidings):
            split = ((robot, origin, room),), *others, ((robot, room, target),)
            yield (*plan[: move.step], *split, *plan[move.step + 1 :])


def _parked_aside(
    clock: TeamClock, plan: Plan, conflict: Conflict, idle: Sequence[str], sidings: int
) -> Iterator[Plan]:
    """Plans whose first step takes a robot of the conflict that makes no move at all (it stands
    at its start, in the other's way for good) into a siding room near where they met, that no
    goal names, before anything else: the push of push-and-swap for a parked robot (office-ros
    with the AMCL model: r2, idle at its start in the corridor, clears r1's way in O7). A robot
    that must end somewhere (goals.ends) stays where it stands."""
    for robot in idle:
        if clock.scenario.goals.end_of(robot) is not None:
            continue
        start = start_location(clock.scenario.robot(robot), clock.lib.world)
        for room in _sidings(clock, conflict, {start}, sidings):
            yield (((robot, start, room),), *plan)


def _sidings(clock: TeamClock, conflict: Conflict, besides: set[str], sidings: int) -> list[str]:
    """Up to ``sidings`` rooms that no goal names, nor ``besides``, nearest to where the
    conflict's robots met."""
    named = set(clock.scenario.goals.all_rooms) | besides
    rooms = [r for r in clock.scenario.places if r.name not in named]
    rooms.sort(key=lambda r: _distance(_centroid(r.polygon), conflict.where))
    return [r.name for r in rooms[:sidings]]


def _first(schedule: Schedule, robot: str) -> TimedMove | None:
    timeline = schedule.timeline(robot)
    return timeline[0] if timeline else None


def _centroid(polygon: Sequence[tuple[float, float]]) -> tuple[float, float]:
    return (sum(p[0] for p in polygon) / len(polygon), sum(p[1] for p in polygon) / len(polygon))


def _distance(a: tuple[float, float], b: tuple[float, float]) -> float:
    return float(((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2) ** 0.5)
