"""The team on one clock: a plan run with every robot moving at once.

A task plan is a sequence of steps (one robot's move, or two robots' paired move), but the
team does not take turns: each robot makes its own moves one after another, and all robots
move at the same time. A move starts as soon as its robot has ended its previous move; a
paired move starts when both of its robots have (the earlier one waits); a move may also
be held back (``delays``: to keep clear of another robot). That is the plan's schedule
(:mod:`tmpnav.task.timing` for moves of known durations).

:meth:`TeamClock.run` executes it on the control steps of the models' ``dt``, one step for
the whole team at a time (the compiled kernel of :mod:`tmpnav.belief.kernel`, the same
prediction and updates as everywhere else):

* every robot that drives applies its control; every robot that stands (waiting for a
  partner, held back, at a station for its job's service time, or done) applies none, so its
  uncertainty does not grow;
* every robot observes the landmarks it sees from its nominal pose, moving or standing;
* any two robots observe each other whenever they are within range and line of sight at
  the same instant (not only the two of a paired move), which couples their beliefs.

When a move starts, the oracle picks its goal instantiation from the belief the robot has
at that instant (the paper's semantic attachment: the pose instantiation in which its
previous move ended starts the next one, with the belief it carries); its nominal motion is
then driven. A move costs the paper's c = M_u c_u + M_G c_G + M_Sigma c_Sigma over its own
motion: control usage, the distance between the mean and the goal pose when it arrives,
and the time integral of trace(Sigma) while it drives. Standing costs nothing in this sum
(the time it takes shows in the makespan, which the time objectives weigh).

The simulated observation noise is drawn so that a robot sees what the oracle's own
simulation of its move sees: a move's landmark draws come from its robot's stream for its
start node, indexed from the move's start, and go on while the robot stands after it; the
two robots of a paired move share the pair's mutual draws for its duration (so a plan of
paired moves only, the paper's, runs exactly as the oracle costed it); other mutual
observations use a stream per ordered pair of robots, by the clock's step.

Between two events the team runs in one joint EKF (:mod:`tmpnav.attachment.joint_window`); where no
robot takes in another, each robot runs along its own moves, propagated once for every run
(:mod:`tmpnav.attachment.own_legs`). The record of a run is :mod:`tmpnav.attachment.record`'s.

The clock's state (:class:`tmpnav.attachment.clock_state.ClockState`) is an immutable value:
:meth:`TeamClock.dispatch` and :meth:`TeamClock.advance` return new ones, so the exact search
can branch from a state
(:mod:`tmpnav.attachment.unfold`).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace

import numpy as np

from tmpnav.attachment.clock_state import ClockRun, ClockState, Leg, MoveRun, Pairing, Unreachable
from tmpnav.attachment.joint_window import JointWindow
from tmpnav.attachment.own_legs import LegBelief, OwnLegs
from tmpnav.attachment.own_runs import RobotRuns
from tmpnav.attachment.record import Trace
from tmpnav.attachment.resume import Checkpoint, Made, Resume, Resumes
from tmpnav.attachment.team import Team
from tmpnav.belief.sequences import EKFConstants
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import NominalMotion, stable_seed
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request, StartState, mutual_seed
from tmpnav.results import Schedule, TimedMove
from tmpnav.task.plans import Plan, Step
from tmpnav.types import CostTerms, MotionResult, cov3, vec3
from tmpnav.world.visibility import MutualSensing


class TeamClock:
    """Runs plans of one scenario's team on the shared clock (see the module docstring)."""

    def __init__(self, oracle: Oracle, lib: MotionLibrary, start: Team):
        self.oracle, self.lib, self.start = oracle, lib, start
        self.scenario = lib.scenario
        self.dt = self.scenario.models.dt
        n = len(start.names)
        self.sensing = {
            (i, j): s
            for i in range(n)
            for j in range(n)
            if i != j and (s := MutualSensing.between(self.scenario, start.names[i], start.names[j])) is not None
        }
        self.ekf = EKFConstants.of(self.scenario.models, lib.world.landmark_xy)
        #: where no robot observes another and none starts correlated with another, each robot's
        #: belief is its own legs' (tmpnav.attachment.own_legs), propagated once for every run
        radii = tuple(self._radius(i) for i in range(n))
        self.own: OwnLegs | None = None
        if not self.sensing and _block_diagonal(start.cov):
            self.own = OwnLegs(lib, self.ekf, radii)
        self.joint = JointWindow(lib, self.ekf, start.names, self.sensing, radii)
        #: the runs made, to resume the next runs of their plans from
        self.resumes: Resumes[ClockState, ClockRun] = Resumes()
        #: a plan of one robot's moves on a team on its own legs is run one robot at a time,
        #: each robot's run kept (tmpnav.attachment.own_runs); False: by the event loop
        self.one_at_a_time = True
        self.robot_runs = RobotRuns(self)

    # ------------------------------------------------------------------ a whole plan

    def run(
        self,
        plan: Plan,
        delays: Mapping[int, float] | None = None,
        record: bool = False,
        detours: Mapping[tuple[int, str], tuple[int, ...]] | None = None,
    ) -> ClockRun:
        """Run ``plan`` (see the module docstring); ``delays`` holds plan steps back by that
        many seconds after they could start; ``detours`` drive (plan step, robot)'s move along
        that roadmap path instead of the shortest one (tmpnav.attachment.detours), when it
        starts and ends where the path does. Raises Unreachable for a step whose robots cannot
        reach their rooms. A run of a plan run before resumes from the last event before the
        first step whose wait or path differs (:mod:`tmpnav.attachment.resume`): the same result."""
        plan = tuple(plan)
        held = {k: v for k, s in (delays or {}).items() if (v := round(s / self.dt))}
        ways = dict(detours or {})
        if self.one_at_a_time and RobotRuns.applies(self, plan):
            return self.robot_runs.run(plan, held, ways, record)
        resume = self.resumes.find(plan, held, ways)
        if resume is not None and resume.at is None:
            return resume.made.run  # the same waits and paths: the run already made
        loop = self._begin(plan, held, record, resume)
        names, order, events, done = self.start.names, loop.order, loop.events, loop.done
        while events:
            loop.mark()
            t, batch = events[0][0], []
            while events and events[0][0] == t:
                batch.append(heapq.heappop(events)[1])
            loop.dispatched.update((k, loop.event) for k in batch)
            loop.state = self.advance(loop.state, t, loop.trace)
            loop.state = self.dispatch(loop.state, [(k, plan[k]) for k in batch], detours=ways)
            for k in batch:
                for m in plan[k]:
                    i = names.index(m[0])
                    done[i] += 1
                    if done[i] < len(order[i]):
                        nxt = order[i][done[i]]
                        if all(done[names.index(r)] == order[names.index(r)].index(nxt) for r, _, _ in plan[nxt]):
                            loop.push(nxt, t)
            loop.event += 1
        state = self.advance(loop.state, max(loop.state.free, default=0), loop.trace)
        result = self._result(state, plan, loop.trace)
        if loop.trace is not None:  # kept to resume from: the runs of a plan kept apart are recorded
            trace, points = loop.trace, tuple(loop.checkpoints)
            made = Made(held, ways, points, loop.pushed, loop.dispatched, trace.steps, trace.segments, result)
            self.resumes.keep(plan, made)
        return result

    def _begin(
        self, plan: Plan, held: dict[int, int], record: bool, resume: Resume[ClockState, ClockRun] | None
    ) -> _Loop:
        """The event loop of a run of ``plan`` at its start, or at ``resume``'s checkpoint."""
        names = self.start.names
        order = [[k for k, step in enumerate(plan) if any(m[0] == r for m in step)] for r in names]
        if resume is None or resume.at is None:
            state = self.initial()
            trace = Trace.at_start(self.dt, state) if record else None
            loop = _Loop(self, plan, held, order, state, [], [0] * len(names), trace)
            loop.event = -1  # the first steps of each robot are scheduled before the first event
            for k, step in enumerate(plan):
                if all(order[names.index(m[0])][0] == k for m in step):
                    loop.push(k, 0)
            loop.event = 0
            return loop
        made, at = resume.made, resume.at
        point = made.checkpoints[at]
        trace = Trace.resumed(self.start.names, self.dt, made.steps, made.segments, point.traced) if record else None
        loop = _Loop(self, plan, held, order, point.state, list(point.events), list(point.done), trace)
        loop.checkpoints = list(made.checkpoints[:at])
        loop.pushed = {k: j for k, j in made.pushed.items() if j < at}
        loop.dispatched = {k: j for k, j in made.dispatched.items() if j < at}
        loop.event = at
        return loop

    def initial(self) -> ClockState:
        """Every robot at its start, with its initial belief, at step 0."""
        team = self.start
        legs = []
        for i, r in enumerate(team.names):
            node, heading = team.node[i], team.heading[i]
            x, y = self.lib.roadmap.nodes[node]
            seed = stable_seed(self.scenario.models.seed, "landmarks", r, node, "standing")
            pose = np.array([x, y, heading])
            key = 0 if self.own is None else self.own.key(i, -1, 0, None, pose, seed)
            legs.append((Leg(0, None, node, heading, pose, seed, key),))
        n = len(team.names)
        # a robot held where it starts (the rest of a service, Goals.held) is free after its hold
        goals = self.scenario.goals
        free = tuple(math.ceil(goals.held_for(r) / self.dt - 1e-9) for r in team.names)
        return ClockState(0, team, tuple(legs), free, (0.0,) * n, (0.0,) * n)

    def ready(self, state: ClockState, step: Step) -> int:
        """The step at which all the robots of ``step`` have ended their latest moves."""
        return max(state.free[self.start.names.index(m[0])] for m in step)

    # ------------------------------------------------------------------ starting moves

    def dispatch(
        self,
        state: ClockState,
        steps: Sequence[tuple[int, Step]],
        results: Sequence[MotionResult | None] | None = None,
        detours: Mapping[tuple[int, str], tuple[int, ...]] | None = None,
    ) -> ClockState:
        """Start ``steps`` (plan index, step) at the clock's time: the oracle picks each move's
        goal instantiation from the robots' beliefs now (one batch of requests, unless their
        ``results`` are given); their motions become their next legs (along a detour's path
        where ``detours`` has one for the move, see :meth:`run`). Raises Unreachable when a
        step's robots cannot reach their rooms."""
        names, t = self.start.names, state.t
        requests = [self.request(state, step) for _, step in steps]
        answers = results if results is not None else self.oracle.evaluate(requests)
        legs, free, pairings, opened = [list(x) for x in state.legs], list(state.free), list(state.pairings), []
        late = state.late
        for (k, step), request, result in zip(steps, requests, answers, strict=True):
            robots = [m[0] for m in step]
            if result is None:
                raise Unreachable(f"{', '.join(robots)} cannot reach {', '.join(request.rooms)} from where they are")
            for r, start, goal in zip(robots, request.starts, result.goal_nodes, strict=True):
                i = names.index(r)
                path = (detours or {}).get((k, r))
                if path is not None and path[0] == start.node and path[-1] == goal:
                    motion: NominalMotion | None = self.lib.along(r, path, start.heading)
                else:
                    motion = self.lib.motion(r, start.node, start.heading, goal)
                assert motion is not None  # the oracle just planned it
                key = 0
                if self.own is not None:
                    key = self.own.key(i, legs[i][-1].key, t, motion, motion.poses[-1], motion.noise_seed)
                legs[i].append(Leg(t, motion, goal, motion.final_heading, motion.poses[-1], motion.noise_seed, key))
                opened.append(MoveRun(k, i, free[i], t, t + motion.n_steps, motion, state.csig[i], state.risk[i]))
                free[i] = t + motion.n_steps
            if len(robots) == 2:
                h = max(free[names.index(r)] for r in robots) - t
                pair = (names.index(robots[0]), names.index(robots[1]))
                pairings.append(Pairing(pair, t, h, mutual_seed(self.lib, tuple(robots), request.starts)))
            for r, _, room in step:  # the job's window and time at the station: it stands, then is free
                i = names.index(r)
                late = late or self.scenario.goals.too_late(room, free[i] * self.dt)
                free[i] += self.opens_steps(room, free[i]) + self.service_steps(room)
        state = replace(
            state,
            legs=tuple(tuple(x) for x in legs),
            free=tuple(free),
            pairings=tuple(pairings),
            open=(*state.open, *opened),
            late=late,
        )
        # a move of no step ends as it starts
        return self._close(state, state.team.mean[None], state.t, [[c] for c in state.csig], [[p] for p in state.risk])

    def opens_steps(self, room: str, arrive: int) -> int:
        """Control steps a robot that arrives at ``room`` at step ``arrive`` waits there for the
        job's window to open (0 without one)."""
        return self.scenario.goals.opens_steps(room, arrive, self.dt)

    def service_steps(self, room: str) -> int:
        """Control steps a robot stands at ``room`` after it arrives, for the room's job: its
        service time rounded up to the clock's steps (0 without a job)."""
        return self.scenario.goals.service_steps(room, self.dt)

    def request(self, state: ClockState, step: Step) -> Request:
        """The oracle's request for ``step`` from where its robots stand now, with their beliefs
        (joint when they are correlated)."""
        team, names = state.team, self.start.names
        idx = [names.index(m[0]) for m in step]
        starts = []
        for i in idx:
            node, heading = state.where(i)
            mean, cov = team.mean[3 * i : 3 * i + 3], team.cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]
            starts.append(StartState(node, float(heading), vec3(mean), cov3(cov)))
        cols = team.cols(idx)
        sub = team.cov[np.ix_(cols, cols)]
        correlated = len(idx) > 1 and bool(np.any(sub[:3, 3:] != 0.0))
        joint = tuple(tuple(float(v) for v in row) for row in sub) if correlated else None
        return Request(tuple(m[0] for m in step), tuple(starts), tuple(m[2] for m in step), joint)

    # ------------------------------------------------------------------ the beliefs

    def advance(self, state: ClockState, until: int, trace: Trace | None = None) -> ClockState:
        """The whole team run from the clock's time to step ``until``: in one joint EKF
        (tmpnav.attachment.joint_window), or each robot along its own moves where none takes in
        another (tmpnav.attachment.own_legs); the moves that end on the way are closed with their
        cost terms."""
        a = state.t
        if until <= a:
            return state
        # the collision bound prices moves only under a threshold; without one, only records need it
        priced = self.scenario.planner.max_risk is not None or trace is not None
        if self.own is not None:
            return self._advance_own(state, until, priced, trace)
        moved, means, running, risk = self.joint.advance(state, until, priced, trace)
        return self._close(moved, means, a, running, risk)

    def _advance_own(self, state: ClockState, until: int, priced: bool, trace: Trace | None) -> ClockState:
        """:meth:`advance` of a team whose robots take in nothing of each other: each robot's belief
        read from its own legs (tmpnav.attachment.own_legs), the team's block-diagonal."""
        own, a, n = self.own, state.t, len(self.start.names)
        assert own is not None
        mean, cov = np.empty(3 * n), np.zeros((3 * n, 3 * n))
        beliefs: list[LegBelief] = []
        for i in range(n):
            legs = state.legs[i]
            r = until - legs[-1].start
            b = own.belief(i, legs, priced, r, self._own_start(i))
            beliefs.append(b)
            mean[3 * i : 3 * i + 3], cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = b.means[b.row(r)], b.covs[b.row(r)]
            if trace is not None:
                lo = a - legs[-1].start + 1
                trace.add(i, own.records(b, lo, r + 1), b, lo, r + 1)
        nodes = tuple(state.where(i)[0] for i in range(n))
        headings = tuple(state.where(i)[1] for i in range(n))
        moved = Team(state.team.names, nodes, headings, mean, cov, until * self.dt)

        def arrived(m: MoveRun) -> tuple[np.ndarray, float, float]:  # its leg's row at its end
            b, k = beliefs[m.robot], m.end - m.start
            return b.means[k, :2], float(b.csig[k]), float(b.risk[k])

        return self._closed(replace(state, t=until, team=moved), arrived)

    def _own_start(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Robot i's initial belief: mean (3,), covariance (3, 3)."""
        s = slice(3 * i, 3 * i + 3)
        return self.start.mean[s], self.start.cov[s, s]

    def _close(
        self,
        state: ClockState,
        means: np.ndarray,
        a: int,
        running: Sequence[Sequence[float]],
        risk: Sequence[Sequence[float]] | Sequence[np.ndarray],
    ) -> ClockState:
        """Close the open moves that have ended by the clock's time: their c_Sigma and
        collision bound from the running sums, c_G from the mean on arrival (``means``,
        ``running``, ``risk``: from step ``a``)."""

        def arrived(m: MoveRun) -> tuple[np.ndarray, float, float]:
            k = m.end - a
            arrival = means[k, 3 * m.robot : 3 * m.robot + 2]
            return arrival, float(running[m.robot][k]) - m.csig_start, float(risk[m.robot][k]) - m.risk_start

        return self._closed(state, arrived)

    def _closed(self, state: ClockState, arrived: Callable[[MoveRun], tuple[np.ndarray, float, float]]) -> ClockState:
        """``state`` with the open moves that have ended by its time closed, each with its cost
        terms: ``arrived`` gives a move's mean position on arrival, its c_Sigma and its collision
        bound (capped at 1 here)."""
        ended = [m for m in state.open if m.end <= state.t]
        if not ended:
            return state
        w, closed = self.scenario.cost, list(state.closed)
        for m in sorted(ended, key=lambda m: (m.end, m.step, m.robot)):
            arrival, c_sigma, bound = arrived(m)
            c_g = float(np.hypot(*(arrival - m.motion.poses[-1, :2])))
            closed.append(replace(m, terms=CostTerms(m.motion.c_u(self.dt), c_g, c_sigma), risk=min(1.0, bound)))
        delta = self.scenario.planner.max_risk
        total = state.closed_cost + sum(m.cost(w, delta) for m in closed[len(state.closed) :])
        still = tuple(m for m in state.open if m.end > state.t)
        return replace(state, open=still, closed=tuple(closed), closed_cost=total)

    def _radius(self, i: int) -> float:
        return self.scenario.robot(self.start.names[i]).radius

    def _result(self, state: ClockState, plan: Plan, trace: Trace | None) -> ClockRun:
        names, dt = self.start.names, self.dt
        moves = sorted(state.closed, key=lambda m: (m.step, m.robot))
        timed = []
        for m in moves:
            step = plan[m.step]
            move = next(x for x in step if x[0] == names[m.robot])
            partner = next((x[0] for x in step if x[0] != names[m.robot]), None)
            service = self.service_steps(move[2]) * dt
            opens = self.opens_steps(move[2], m.end) * dt
            timed.append(
                TimedMove(
                    m.step, move[0], move[1], move[2], partner, m.ready * dt, m.start * dt, m.end * dt, service, opens
                )
            )
        if trace is None:
            return ClockRun(moves, Schedule(names, tuple(timed)), state)
        return ClockRun(moves, Schedule(names, tuple(timed)), state, trace.trajectories(), trace.tracks())


class _Loop:
    """A run's event loop as it goes: the clock's state, the events to come (a heap of
    (control step, plan step)), each robot's steps dispatched, the record, and for
    :mod:`tmpnav.attachment.resume` the checkpoints and the event that scheduled and that
    started each step."""

    def __init__(
        self,
        clock: TeamClock,
        plan: Plan,
        held: Mapping[int, int],
        order: list[list[int]],
        state: ClockState,
        events: list[tuple[int, int]],
        done: list[int],
        trace: Trace | None,
    ):
        self.clock, self.plan, self.held, self.order = clock, plan, held, order
        self.state, self.events, self.done, self.trace = state, events, done, trace
        self.checkpoints: list[Checkpoint[ClockState]] = []
        self.pushed: dict[int, int] = {}
        self.dispatched: dict[int, int] = {}
        self.event = 0

    def push(self, k: int, after: int) -> None:
        """Schedule step k when its robots are free, not before ``after``, held back its wait."""
        start = max(self.clock.ready(self.state, self.plan[k]), after) + self.held.get(k, 0)
        heapq.heappush(self.events, (start, k))
        self.pushed[k] = self.event

    def mark(self) -> None:
        """A checkpoint at the top of the current event, where the run is recorded (only recorded
        runs are kept to resume from)."""
        if self.trace is not None:
            self.checkpoints.append(Checkpoint(self.state, tuple(self.events), tuple(self.done), self.trace.lengths()))


def _block_diagonal(cov: np.ndarray) -> bool:
    """Whether a team's covariance (3n, 3n) correlates no two robots."""
    n = cov.shape[0] // 3
    mask = np.kron(np.eye(n, dtype=bool), np.ones((3, 3), dtype=bool))
    return not bool(np.any(cov[~mask] != 0.0))
