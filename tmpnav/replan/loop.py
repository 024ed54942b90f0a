"""The closed loop of ``tmpnav simulate --events`` (docs/replan.md, "Closed loop").

The team executes its plan as ``tmpnav simulate`` does (:class:`tmpnav.execution.Session`: true
poses, noisy controls and sensors, the joint EKF with mutual observations), and the world
changes under it as the EVENTS file says (:mod:`tmpnav.replan.events`): a robot stops or slows
for a while, a robot goes down, a door closes, goals arrive or are cancelled. The team replans
(:func:`tmpnav.replan._revised`, what ``tmpnav replan`` runs) from its state at that instant:

- at every event that changes the problem (a robot down, a door, goals);
- when a robot falls behind its plan by more than ``late`` s (its move under way should have
  ended, or its next move should have started, that long ago): how a stop or a slowdown shows.
  Lateness is the trigger, not a distance of the beliefs: the planned beliefs are those of the
  plan's own paths, and the executing filter's agree with them (NEES near 2, ``tmpnav simulate``),
  while a robot that is held up is late whatever its belief.

Each robot's state is its filter's estimate and covariance (its block of the joint belief); the
rooms done are those the session's moves ended in; the rest of the queues, in plan order, is the
search's incumbent. The simulated clock stands still while the team replans; each replan's
wall-clock latency is recorded. The new plan's moves go on from where the robots are.

Every session is also executed two other ways, on the same random draws:

- **blind**: the first plan, never revised, with the same events (a robot down stays down, a
  closed door stays closed; added goals are never done);
- **knowing the events**: a plan made at the start with every event's change of the problem
  known (the doors as they end up, the goals added and removed, the robots that go down left out
  of the team from the start), executed with the same stops and slowdowns. Its executed
  makespan is the reference of the closed loop's.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tmpnav.errors import TmpnavError
from tmpnav.execution import STEP_BUDGET, Draws, QueuedMove, Session, queues
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import queues_of_document
from tmpnav.replan.events import Event, Events
from tmpnav.replan.loop_report import MODES, LoopResult, Replan, Run
from tmpnav.replan.remote import NothingLeftRemote, RemotePlans, at_start_of_document, unreachable_of_document
from tmpnav.replan.revise import NothingLeft
from tmpnav.replan.state import RobotState, TeamState
from tmpnav.results import PlanReport
from tmpnav.types import Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility

if TYPE_CHECKING:
    from tmpnav.pipeline import PlanOptions

#: replans one session may make at most (a robot stuck for ever would otherwise replan every ``late`` s)
MAX_REPLANS = 20
#: m: how far from its estimate a robot's start may be put to find free space for a replan
NUDGE = 0.6


@dataclass
class _Context:
    """What the sessions share: the scenario loaded once, its worlds by door states, the options."""

    path: str | Path
    loaded: tuple[Scenario, World]
    options: PlanOptions
    events: Events
    seed: int
    worlds: dict[tuple[tuple[str, bool], ...], tuple[World, LandmarkVisibility]] = field(default_factory=dict)
    localisation: Localisation | None = None  # who localises the robots (tmpnav's EKF when None)
    server: str | None = None  # the closed loop's plans come from tmpnav serve at this URL
    token: str | None = None  # the service's --token

    @property
    def scenario(self) -> Scenario:
        return self.loaded[0]

    def world(self, doors: dict[str, bool]) -> tuple[World, LandmarkVisibility]:
        """The world with these doors open (True) or closed, and its landmarks' visibility."""
        from tmpnav.world.build import build

        key = tuple(sorted(doors.items()))
        if key not in self.worlds:
            scenario, world = self.loaded
            if doors:
                scenario = replace(
                    scenario, doors=tuple(replace(d, open=doors.get(d.name, d.open)) for d in scenario.doors)
                )
                world = build(scenario)
            self.worlds[key] = (world, LandmarkVisibility(world, scenario.models.landmark_sensor.range))
        return self.worlds[key]

    def draws(self, session: int, planned: PlanReport) -> Draws:
        """The session's draws, long enough for the slowest of its executions."""
        scenario, world = self.loaded
        steps = sum(len(t) for t in planned.trajectories.values())
        held = sum(e.seconds for e in self.events.events if e.kind in ("stop", "slow"))
        sensor = scenario.models.range_sensor
        return Draws.draw(
            self.seed,
            session,
            len(scenario.robots),
            STEP_BUDGET * (steps + round(held / scenario.models.dt)) + 100,
            world.landmark_xy.shape[0],
            sensor.beams if sensor is not None else 0,
        )


def closed_loop(
    path: str | Path,
    events: Events,
    sessions: int,
    seed: int = 0,
    options: PlanOptions | None = None,
    progress: Callable[[str], None] | None = None,
    localisation: Localisation | None = None,
    server: str | None = None,
    token: str | None = None,
) -> LoopResult:
    """Plan ``path``, then execute it ``sessions`` times in the three :data:`MODES`, the robots
    localised as ``localisation`` says (tmpnav's EKF when None). With ``server``, the closed
    loop's plans come from the ``tmpnav serve`` at that URL (:mod:`tmpnav.replan.remote`)."""
    from tmpnav import pipeline

    options = options or pipeline.PlanOptions()
    loaded = pipeline.load_world(path, options.overrides)
    ctx = _Context(path, loaded, options, events, seed, localisation=localisation, server=server, token=token)
    planned = pipeline.plan(path, options, loaded=loaded)
    informed, why = _informed(ctx, planned)
    say = progress or (lambda _: None)
    runs: dict[str, list[Run]] = {m: [] for m in MODES}
    for s in range(sessions):
        runs["closed loop"].append(_execute(ctx, planned, s, replanning=True, say=say))
        runs["blind"].append(_execute(ctx, planned, s, replanning=False))
        if informed is not None:
            runs["knowing the events"].append(_execute(ctx, informed, s, replanning=False, known=True))
    return LoopResult(events, planned, informed, why, runs, server)


def _informed(ctx: _Context, planned: PlanReport) -> tuple[PlanReport | None, str]:
    """The plan made at the start knowing every event's change of the problem (module docstring)."""
    doors: dict[str, bool] = {}
    down: list[str] = []
    add: list[str] = []
    remove: list[str] = []
    for e in ctx.events.events:
        _changes(e, doors, down, add, remove)
    if not doors and not down and not add and not remove:
        return planned, ""
    team = TeamState(
        ctx.events.source,
        0.0,
        {r: RobotState(r, down=True) for r in down},
        (),
        dict(doors),
        tuple(add),
        tuple(remove),
    )
    try:
        return _plan(ctx, planned, team, None), ""
    except TmpnavError as err:
        return None, str(err)


def _changes(e: Event, doors: dict[str, bool], down: list[str], add: list[str], remove: list[str]) -> None:
    """Fold one event's change of the problem into the doors, robots down and goals so far."""
    if e.kind in ("close", "open"):
        assert e.door is not None
        doors[e.door] = e.kind == "open"
    elif e.kind == "down":
        assert e.robot is not None
        down.append(e.robot)
    elif e.kind == "goals":
        for x in e.add:
            if x in remove:
                remove.remove(x)
            add.append(x)
        for x in e.remove:
            if x in add:
                add.remove(x)
            remove.append(x)


def _plan(
    ctx: _Context,
    current: PlanReport,
    team: TeamState,
    incumbent: tuple[tuple[tuple[str, str], ...], ...] | None,
) -> PlanReport:
    """The revision of ``current`` from ``team`` (what ``tmpnav replan`` plans), its risk accepted:
    a team under way cannot stop for a plan over its threshold."""
    from tmpnav.replan import _revised
    from tmpnav.report.plan_json import plan_document

    doc = json.loads(json.dumps(plan_document(current)))
    number = current.revision.number if current.revision is not None else 0
    options = ctx.options.but(accept_risk=True, progress=None, search_progress=None)
    return _revised(ctx.path, ctx.loaded, Path(f"revision-{number}"), doc, team, options, incumbent, within=False)


def _execute(
    ctx: _Context,
    plan: PlanReport,
    s: int,
    replanning: bool,
    known: bool = False,
    say: Callable[[str], None] = lambda _: None,
) -> Run:
    """Session ``s`` of ``plan`` with the events; replanning (the closed loop) or not."""
    scenario = ctx.scenario
    names = [r.name for r in scenario.robots]
    dt = scenario.models.dt
    doors: dict[str, bool] = {}
    down: list[str] = []
    add: list[str] = []
    remove: list[str] = []
    if known:  # the plan knew every change of the problem: the world is as the events leave it
        for e in ctx.events.events:
            _changes(e, doors, down, add, remove)
    source = _Remote(ctx) if replanning and ctx.server else _Local(ctx, plan)
    session = Session(
        scenario, ctx.loaded[1], source.first(plan), ctx.draws(s, plan), ctx.world({})[1], True, ctx.localisation, s
    )
    if doors:
        session.set_world(*ctx.world(doors))
    for r in down:
        session.set_down(r)
    pending = [e for e in ctx.events.events if not (known and e.replans)]
    restore: list[tuple[int, int]] = []  # (step, robot index) at which a stop or slowdown ends
    start, checked = 0, 0
    replans: list[Replan] = []
    dropped: list[str] = []
    at_start = source.at_start  # goals a robot visits by starting in them (revision by revision)
    late_steps = max(1, round(ctx.events.late / dt))

    def due() -> bool:
        now = session.step
        if any(round(e.at / dt) <= now for e in pending) or any(k <= now for k, _ in restore):
            return True
        return replanning and now - checked >= late_steps and _lateness(session, down) >= late_steps

    while True:
        session.run(due)
        if session.finished and not (pending and replanning):
            break
        if session.finished:  # the team is done before an event: its clock jumps there
            session.step = max(session.step, min(round(e.at / dt) for e in pending))
        now = session.step
        for k, i in [x for x in restore if x[0] <= now]:
            restore.remove((k, i))
            if i not in session.down:
                session.speed[i] = 1.0
        happened = [e for e in pending if round(e.at / dt) <= now]
        pending = [e for e in pending if e not in happened]
        reasons = []
        for e in happened:
            if e.kind in ("stop", "slow"):
                i = names.index(e.robot or "")
                if i not in session.down:
                    session.speed[i] = 0.0 if e.kind == "stop" else e.factor
                    restore.append((now + round(e.seconds / dt), i))
                continue
            _changes(e, doors, down, add, remove)
            if e.kind == "down":
                session.set_down(e.robot or "")
            elif e.kind in ("close", "open"):
                session.set_world(*ctx.world(doors))
            reasons.append(e.text())
        if not replanning:
            continue
        if not reasons and now - checked >= late_steps:
            late = _lateness(session, down)
            if late >= late_steps:
                reasons.append(f"late by {late * dt:.1f} s")
        checked = now
        if not reasons or len(replans) >= MAX_REPLANS:
            continue
        team = _team(ctx, session, start, doors, down, add, remove, at_start)
        began = time.perf_counter()
        unreachable: tuple[str, ...] = ()
        try:
            revised, unreachable, starts = source.revise(
                team, _incumbent(session, down, set(team.visited or ()) | set(remove))
            )
        except (NothingLeft, NothingLeftRemote):
            session.adopt({})
            outcome = "nothing left"
        except TmpnavError as err:
            outcome = f"failed: {err}"
        else:
            dropped += [x for x in unreachable if x not in dropped]
            session.adopt(revised)
            at_start += [x for x in starts if x not in at_start]
            start, outcome = now, "planned"
        latency = time.perf_counter() - began
        replans.append(Replan(s, now * dt, "; ".join(reasons), latency, outcome, unreachable))
        say(f"session {s + 1}: t = {now * dt:.1f} s, {'; '.join(reasons)}: replanned in {latency:.1f} s ({outcome})")
    if known and plan.revision is not None:
        dropped = [room for room, _ in plan.revision.unreachable]
    mode = MODES[0] if replanning else MODES[2] if known else MODES[1]
    return _run(ctx, session, s, mode, add, remove, down, dropped, replans, at_start)


Queues = dict[str, tuple[QueuedMove, ...]]


class _Local:
    """The closed loop's revisions planned in this process, as ``tmpnav replan`` plans them."""

    def __init__(self, ctx: _Context, plan: PlanReport):
        self.ctx, self.current = ctx, plan
        self.at_start = _at_start(plan)

    def first(self, plan: PlanReport) -> Queues:
        return queues(plan)

    def revise(
        self, team: TeamState, incumbent: tuple[tuple[tuple[str, str], ...], ...]
    ) -> tuple[Queues, tuple[str, ...], list[str]]:
        """The revision's queues, the rooms it names out of reach and those its robots start in."""
        revised = _plan(self.ctx, self.current, team, incumbent)
        assert revised.revision is not None
        self.current = revised
        return queues(revised), tuple(room for room, _why in revised.revision.unreachable), _at_start(revised)


class _Remote:
    """The closed loop's plan and revisions asked of ``tmpnav serve`` (:mod:`tmpnav.replan.remote`):
    a plan of its own for each session, as the team's state changes."""

    def __init__(self, ctx: _Context):
        assert ctx.server is not None
        self.ctx, self.plans = ctx, RemotePlans.at(ctx.server, ctx.token)
        self.at_start: list[str] = []

    def first(self, plan: PlanReport) -> Queues:
        doc = self.plans.first(plan.roadmap.fingerprint, str(self.ctx.path))
        self.at_start = at_start_of_document(doc)
        return queues_of_document(doc)

    def revise(
        self, team: TeamState, incumbent: tuple[tuple[tuple[str, str], ...], ...]
    ) -> tuple[Queues, tuple[str, ...], list[str]]:
        """As :meth:`_Local.revise`; the service starts its search from its own plan, not ``incumbent``."""
        doc = self.plans.revise(team)
        return queues_of_document(doc), unreachable_of_document(doc), at_start_of_document(doc)


def _lateness(session: Session, down: list[str]) -> int:
    """Control steps by which the latest robot is behind its plan: its move under way should have
    ended, or its next move should have started, that long ago (0 when none is)."""
    worst = 0
    for i, r in enumerate(session.robots):
        if session.names[i] in down:
            continue
        if r.move is not None:
            worst = max(worst, session.step - (r.move.start + r.move.steps))
        elif r.next is not None and r.ready <= session.step:
            worst = max(worst, session.step - r.next.start)
    return worst


def _at_start(plan: PlanReport) -> list[str]:
    """The goal rooms the plan has visited by its robots' starts (a robot that starts in a room
    it is to visit has visited it)."""
    goals, where = plan.scenario.goals, plan.table.start_location
    shared = [x for x in goals.visit if x in where.values()]
    return list(dict.fromkeys([*shared, *(x for _, x in sorted(goals.marked_at_start(where)))]))


def _team(
    ctx: _Context,
    session: Session,
    start: int,
    doors: dict[str, bool],
    down: list[str],
    add: list[str],
    remove: list[str],
    at_start: list[str],
) -> TeamState:
    """The team's state now: each live robot's estimate and covariance, the rooms done (entered by
    a move, or visited by starting there)."""
    dt = ctx.scenario.models.dt
    world = session.world
    robots: dict[str, RobotState] = {}
    for i, spec in enumerate(ctx.scenario.robots):
        if spec.name in down:
            robots[spec.name] = RobotState(spec.name, down=True)
            continue
        mean = session.estimate(i)
        x, y = _free_near(world, float(mean[0]), float(mean[1]), spec.radius)
        block = session.estimate_cov(i)
        cov = tuple(tuple(float(v) for v in row) for row in 0.5 * (block + block.T))
        robots[spec.name] = RobotState(spec.name, (x, y, float(mean[2])), cov)  # type: ignore[arg-type]
    entered = [m.target for m in session.trace.reached()]
    done = tuple(dict.fromkeys([*at_start, *entered]))
    return TeamState(
        ctx.events.source, (session.step - start) * dt, robots, done, dict(doors), tuple(add), tuple(remove)
    )


def _free_near(world: World, x: float, y: float, radius: float) -> tuple[float, float]:
    """(x, y), or the nearest free point within :data:`NUDGE` m of it on rings of the map's cells
    (an estimate that grazes a wall: the planner starts a robot in free space)."""
    if bool(world.is_free(np.array([[x, y]]), radius)[0]):
        return x, y
    res = float(world.grid.resolution)
    for ring in np.arange(res, NUDGE + res / 2, res):
        angles = np.linspace(0.0, 2 * math.pi, max(8, int(2 * math.pi * ring / res)), endpoint=False)
        points = np.column_stack([x + ring * np.cos(angles), y + ring * np.sin(angles)])
        free = world.is_free(points, radius)
        if free.any():
            k = int(np.flatnonzero(free)[0])
            return float(points[k, 0]), float(points[k, 1])
    return x, y  # the planner names the pose as inside a wall


def _incumbent(session: Session, down: list[str], gone: set[str]) -> tuple[tuple[tuple[str, str], ...], ...]:
    """The rest of the session's queues (moves under way, then queued), grouped by plan step in
    plan order, without the robots down and the rooms done or removed: the search's warm start."""
    steps: dict[int, list[tuple[str, str]]] = {}
    for i, r in enumerate(session.robots):
        name = session.names[i]
        if name in down:
            continue
        rest: list[QueuedMove] = ([r.move] if r.move is not None else []) + list(r.queue[r.started :])
        for m in rest:
            if m.target not in gone:
                steps.setdefault(m.step, []).append((name, m.target))
    return tuple(tuple(steps[k]) for k in sorted(steps))


def _run(
    ctx: _Context,
    session: Session,
    s: int,
    mode: str,
    add: list[str],
    remove: list[str],
    down: list[str],
    dropped: list[str],
    replans: list[Replan],
    at_start: list[str],
) -> Run:
    """What the session did: the goals done (and twice), dropped, its makespan, cost and collisions."""
    scenario = ctx.scenario
    goals = scenario.goals
    required = [x for x in (*goals.all_rooms, *add) if x not in remove]
    ends_of_down = [x for r, x in goals.ends if r in down]
    required = [x for x in dict.fromkeys(required) if x not in ends_of_down]
    trace = session.trace
    entered: dict[str, int] = dict.fromkeys(at_start, 1)
    for m in trace.reached():
        entered[m.target] = entered.get(m.target, 0) + 1
    done = tuple(x for x in entered if x in required)
    twice = tuple(x for x in done if entered[x] > 1)
    cost = sum(float(scenario.cost.combine(trace.c_u[r], trace.c_goal[r], trace.c_sigma[r])) for r in trace.c_u)
    return Run(
        mode,
        s,
        tuple(required),
        done,
        twice,
        tuple(x for x in dropped if x in required),
        max((m.done for m in trace.moves), default=0.0),
        cost,
        sum(trace.wall_hits.values()),
        sum(trace.contacts.values()),
        replans,
    )
