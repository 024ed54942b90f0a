"""Costs from the beliefs the robots carry: the paper's semantic attachment, step by step.

The paper's module evaluates an action from the belief the search has reached: the pose
instantiation and the belief in which the robot's previous move ended start its next move.
:class:`CarriedCosts` does exactly that for whole plans. A plan's steps run in order on the
team's joint belief (one EKF state over every robot, cross-correlations included): each
step asks the oracle for the action from where its robots actually are, with their actual
beliefs (their joint covariance when earlier steps correlated them), and the chosen motions
are then propagated through the joint state. Robots that do not move stay put and take no
part in the observations; their beliefs change only through their correlations with the
robots that move. A step's cost is the weighted cost of its robots' motions.

This is also what the re-simulation of the final plan does (:mod:`tmpnav.resimulate` calls
:meth:`CarriedCosts.replay`, which runs the same steps and records every control step), so
with ``--costs carried`` the cost the planner minimises is the executed cost, number for number.

Two facts keep it fast without changing any number:

* only the robots that move and those correlated with them take part in a step: for every
  other robot nothing changes (zero cross-covariance, no motion, no observation), so the
  step runs on that sub-team and the rest of the joint state is copied;
* a step's outcome depends only on that sub-team's state and the step, so it is memoised:
  re-costing a plan after the search changed one robot's route re-simulates only the
  steps whose starting beliefs changed.

For the search's sub-problems (:meth:`CarriedCosts.subtable`), the first move of each robot
is costed from its actual belief at that point of the plan; a later move between two of the
sub-problem's rooms from the state in which the robot arrives in the first room driving
there directly from where it is (the table's canonical rule, applied at that point of the
plan). Each plan the search keeps is then costed in full, step by step as above.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tmpnav.attachment.canonical import CanonicalCosts, _offered, _ordered
from tmpnav.attachment.team import Team, belief_step, mutual_sensing, stationary
from tmpnav.choices import Costs
from tmpnav.errors import TmpnavError
from tmpnav.oracle.executors import library
from tmpnav.oracle.motionsets import trajectory
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request, StartState
from tmpnav.oracle.table import arrival_state
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.model import PlanCost, sub_moves
from tmpnav.task.plans import Plan, Step
from tmpnav.types import CostTable, CostTerms, Goals, MotionResult, MoveKey, TrajectoryStep, vec3


@dataclass(frozen=True, eq=False)
class StepOutcome:
    """One plan step run on the team: its cost, what each moving robot did, the new state."""

    cost: float
    robots: tuple[str, ...]
    terms: tuple[CostTerms, ...]  # per moving robot
    goal_nodes: tuple[int, ...]
    paths: tuple[tuple[int, ...], ...]
    goal_poses: tuple[tuple[float, float, float], ...]
    team: Team  # the state after the step
    trajectories: dict[str, list[TrajectoryStep]] | None = None  # replayed steps: each mover's beliefs


class CarriedCosts:
    """Plan costs with carried-over beliefs (the module docstring); a :class:`~tmpnav.task.model.CostModel`."""

    costs: Costs = "carried"

    def __init__(self, oracle: Oracle, canonical: CanonicalCosts):
        self.oracle = oracle
        self.canonical = canonical
        self.scenario = oracle.ctx.scenario
        self.lib = library(oracle.ctx)
        self.robots = canonical.robots
        self.start_location = canonical.start_location
        self.min_gain = canonical.min_gain
        self.start = Team.at_start(self.lib, self.scenario)
        self._memo: dict[bytes, tuple[StepOutcome, list[int]]] = {}
        self._pruned: set[bytes] = set()  # paired steps the oracle proved unable to save min_gain
        self.steps_simulated = 0

    # ------------------------------------------------------------------ CostModel

    def singles(self, goals: Goals) -> CostTable:
        """The single moves from canonical states: the search's first plan is routed on them."""
        return self.canonical.singles(goals)

    def plan_cost(self, plan: Plan) -> PlanCost:
        team, costs = self.start, []
        for step in plan:
            try:
                outcome = self.advance(team, step)
            except Unreachable:
                return PlanCost.impossible(len(plan))
            costs.append(outcome.cost)
            team = outcome.team
        return PlanCost(float(sum(costs)), tuple(costs))

    def state_after(self, head: Plan) -> Team:
        team = self.start
        for step in head:
            team = self.advance(team, step).team
        return team

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        team = self.state_after(head)
        idx = {r: team.names.index(r) for r in robots}
        at = {r: _location(self.start_location[r], head, r) for r in robots}
        first = [(r, at[r], t) for r in robots for t in rooms if t != at[r]]
        results = self.oracle.evaluate([team.request([r], [t]) for r, _, t in first])
        single: dict[MoveKey, float] = {}
        arrived: dict[tuple[str, str], StartState] = {}
        for move, res in zip(first, results, strict=True):
            if res is not None:
                single[move] = res.cost
                arrived[(move[0], move[2])] = arrival_state(res)
        later = [m for m in sub_moves(at, rooms) if m[1] != at[m[0]] and (m[0], m[1]) in arrived]
        results = self.oracle.evaluate([Request((r,), (arrived[(r, o)],), (t,)) for r, o, t in later])
        single.update({m: res.cost for m, res in zip(later, results, strict=True) if res is not None})
        pair = self._pairs(team, idx, at, arrived, single, goals)
        locations = tuple(dict.fromkeys([*rooms, *at.values()]))
        return CostTable(tuple(robots), tuple(rooms), locations, at, single, pair)

    def _pairs(
        self,
        team: Team,
        idx: dict[str, int],
        at: dict[str, str],
        arrived: dict[tuple[str, str], StartState],
        single: dict[MoveKey, float],
        goals: Goals,
    ) -> dict[tuple[MoveKey, MoveKey], float]:
        """Paired moves of the sub-problem that save at least ``min_gain``: from the robots'
        actual joint belief when both make their first move, else from their arrival states."""
        keep = ENCODINGS["mixed"].pair_filter(goals, at)
        assert keep is not None
        moves = list(single)
        wanted = [
            _ordered(m1, m2, self.robots)
            for i, m1 in enumerate(moves)
            for m2 in moves[i + 1 :]
            if m1[0] != m2[0] and keep(m1, m2)
        ]
        requests = []
        for m1, m2 in wanted:
            if m1[1] == at[m1[0]] and m2[1] == at[m2[0]]:
                req = team.request([m1[0], m2[0]], [m1[2], m2[2]])
            else:
                s1 = team.start_state(idx[m1[0]]) if m1[1] == at[m1[0]] else arrived[(m1[0], m1[1])]
                s2 = team.start_state(idx[m2[0]]) if m2[1] == at[m2[0]] else arrived[(m2[0], m2[1])]
                req = Request((m1[0], m2[0]), (s1, s2), (m1[2], m2[2]))
            gain = self.min_gain if self.min_gain > 0 and req.joint_cov is None else None
            requests.append(Request(req.robots, req.starts, req.rooms, req.joint_cov, min_gain=gain))
        out = {}
        for p, res in zip(wanted, self.oracle.evaluate(requests), strict=True):
            if res is not None and not res.pruned and _offered(res.cost, single[p[0]] + single[p[1]], self.min_gain):
                out[p] = res.cost
        return out

    # ------------------------------------------------------------------ one step

    def advance(self, team: Team, step: Step) -> StepOutcome:
        """Run one plan step on ``team`` (raises TmpnavError if its robots cannot reach
        their rooms)."""
        robots = tuple(m[0] for m in step)
        idx = [team.names.index(r) for r in robots]
        sub = team.partners(idx)
        key = self._key(team, step, sub)
        if key in self._memo:
            outcome, _ = self._memo[key]
            return self._apply(team, sub, outcome)
        outcome = self._run(team, step, idx, sub, False)
        self._memo[key] = (outcome, sub)
        return self._apply(team, sub, outcome)

    def replay(self, plan: Plan) -> list[StepOutcome]:
        """Run the plan's steps in order from the start, as :meth:`plan_cost` does, and record
        each moving robot's belief at every control step (``StepOutcome.trajectories``).
        Raises TmpnavError naming the first step whose robots cannot reach their rooms."""
        team, outcomes = self.start, []
        for k, step in enumerate(plan):
            robots = tuple(m[0] for m in step)
            idx = [team.names.index(r) for r in robots]
            sub = team.partners(idx)
            try:
                outcome = self._apply(team, sub, self._run(team, step, idx, sub, True))
            except TmpnavError as err:
                raise TmpnavError(f"plan step {k + 1}: {err}") from None
            outcomes.append(outcome)
            team = outcome.team
        return outcomes

    def advance_many(
        self, team: Team, steps: Sequence[Step], min_gain: float | None = None
    ) -> list[StepOutcome | None]:
        """Every step of ``steps`` run on ``team`` (its oracle requests in one batch); None
        for a step whose robots cannot reach their rooms, and with ``min_gain`` for a paired
        step the oracle proves unable to save that much over its two moves made alone from
        ``team`` (it is then not simulated)."""
        todo: dict[int, tuple[list[int], list[int], bytes]] = {}
        out: list[StepOutcome | None] = [None] * len(steps)
        for n, step in enumerate(steps):
            idx = [team.names.index(m[0]) for m in step]
            sub = team.partners(idx)
            key = self._key(team, step, sub)
            if key in self._memo:
                out[n] = self._apply(team, sub, self._memo[key][0])
            elif key not in self._pruned:
                todo[n] = (idx, sub, key)
        requests = []
        for n in todo:
            req = team.request([m[0] for m in steps[n]], [m[2] for m in steps[n]])
            gain = min_gain if min_gain and len(steps[n]) == 2 and req.joint_cov is None else None
            requests.append(Request(req.robots, req.starts, req.rooms, req.joint_cov, min_gain=gain))
        for (n, (idx, sub, key)), result in zip(todo.items(), self.oracle.evaluate(requests), strict=True):
            if result is None or result.pruned:
                if result is not None:
                    self._pruned.add(key)
                continue
            outcome = self._run(team, steps[n], idx, sub, False, result)
            self._memo[key] = (outcome, sub)
            out[n] = self._apply(team, sub, outcome)
        return out

    def _run(
        self, team: Team, step: Step, idx: list[int], sub: list[int], record: bool, result: MotionResult | None = None
    ) -> StepOutcome:
        lib = self.lib
        robots = tuple(m[0] for m in step)
        request = team.request(robots, [m[2] for m in step])
        if result is None:
            result = self.oracle.evaluate([request])[0]
        if result is None:
            raise Unreachable(f"{', '.join(robots)} cannot reach {', '.join(request.rooms)} from where they are")
        motions = []
        for j in sub:
            if j in idx:
                k = idx.index(j)
                m = lib.motion(team.names[j], team.node[j], team.heading[j], result.goal_nodes[k])
                assert m is not None  # the oracle just planned it
                motions.append(m)
            else:
                motions.append(stationary(lib, team.names[j], team.node[j], team.heading[j]))
        h = max(m.n_steps for m in motions)
        movers = [sub.index(j) for j in idx]
        mvis, mu_noise = mutual_sensing(lib, motions, movers, robots, request.starts, h)
        cols = team.cols(sub)
        run = trajectory(lib, motions, team.mean[cols], team.cov[np.ix_(cols, cols)], mvis, mu_noise)
        dt = self.scenario.models.dt
        trajectories = None
        if record:
            trajectories = {}
            for j, s in zip(idx, movers, strict=True):
                m = motions[s]
                reached = dict(zip(m.node_steps.tolist(), m.path, strict=False))
                trajectories[team.names[j]] = [
                    belief_step(team.t + q * dt, run.means[q], run.covs[q], s, reached.get(q)) for q in range(1, h + 1)
                ]
        self.steps_simulated += 1
        new = Team(
            tuple(team.names[j] for j in sub),
            tuple(motions[s].path[-1] for s in range(len(sub))),
            tuple(motions[s].final_heading for s in range(len(sub))),
            run.means[-1],
            run.covs[-1],
            h * dt,  # the step's duration
        )
        terms = tuple(run.terms[s] for s in movers)
        return StepOutcome(
            cost=float(sum(t.total(self.scenario.cost) for t in terms)),
            robots=robots,
            terms=terms,
            goal_nodes=result.goal_nodes,
            paths=tuple(motions[s].path for s in movers),
            goal_poses=tuple(vec3(motions[s].poses[-1]) for s in movers),
            team=new,
            trajectories=trajectories,
        )

    def _apply(self, team: Team, sub: list[int], outcome: StepOutcome) -> StepOutcome:
        """The outcome with ``team`` updated: the sub-team's state replaced, time advanced."""
        part = outcome.team
        node, heading = list(team.node), list(team.heading)
        for s, j in enumerate(sub):
            node[j], heading[j] = part.node[s], part.heading[s]
        cols = team.cols(sub)
        mean, cov = team.mean.copy(), team.cov.copy()
        mean[cols] = part.mean
        cov[np.ix_(cols, cols)] = part.cov
        new = Team(team.names, tuple(node), tuple(heading), mean, cov, team.t + part.t)
        return StepOutcome(
            outcome.cost,
            outcome.robots,
            outcome.terms,
            outcome.goal_nodes,
            outcome.paths,
            outcome.goal_poses,
            new,
            outcome.trajectories,
        )

    def _key(self, team: Team, step: Step, sub: list[int]) -> bytes:
        """What a step's outcome depends on: the step, and the sub-team's state."""
        cols = team.cols(sub)
        h = hashlib.blake2b(repr((step, [team.names[j] for j in sub])).encode(), digest_size=20)
        h.update(np.array([team.node[j] for j in sub], dtype=np.int64).tobytes())
        h.update(np.array([team.heading[j] for j in sub], dtype=np.float64).tobytes())
        h.update(np.ascontiguousarray(team.mean[cols]).tobytes())
        h.update(np.ascontiguousarray(team.cov[np.ix_(cols, cols)]).tobytes())
        return h.digest()


class Unreachable(TmpnavError):
    """A plan step whose robots cannot reach their rooms from where they are."""


def _location(start: str, head: Plan, robot: str) -> str:
    where = start
    for step in head:
        for r, _, t in step:
            if r == robot:
                where = t
    return where
