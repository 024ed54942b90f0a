"""Stage 7: the task-motion plan, re-simulated with beliefs carried from action to action.

The cost table starts every move from a canonical state (see :mod:`tmpnav.oracle.table`).
Here the plan's actions run in order from the robots' true situation: each action starts
where its robots actually are, with their actual beliefs, cross-correlations included,
and the oracle picks its goal instantiations again from there (paper: "this instantiation
becomes the start node" of the next move). The whole team is one joint EKF state: robots
that do not move in an action stay still, neither observe nor are observed, and their
beliefs change only through their correlations with the robots that move.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tmpnav.errors import TmpnavError
from tmpnav.oracle.evaluate import Request, StartState, mutual_seed, trajectory
from tmpnav.oracle.motions import MotionLibrary, NominalMotion
from tmpnav.oracle.oracle import Oracle
from tmpnav.types import (
    Belief,
    CostTerms,
    MotionResult,
    MoveKey,
    PlannedAction,
    Scenario,
    TrajectoryStep,
    cov3,
    vec3,
)
from tmpnav.world.visibility import MutualSensing


@dataclass
class Resimulation:
    """The plan re-simulated: its actions with their costs, each robot's belief at every
    step, each robot's cost terms per move, and the team's joint belief at the end."""

    actions: list[PlannedAction]
    trajectories: dict[str, list[TrajectoryStep]]
    terms: dict[str, list[CostTerms]] = field(default_factory=dict)
    final: Belief | None = None

    @property
    def cost(self) -> float:
        return sum(a.resimulated_cost for a in self.actions)


def _stationary(lib: MotionLibrary, robot: str, node: int, heading: float) -> NominalMotion:
    """A robot that stays put during an action: no steps, no observations."""
    x, y = lib.roadmap.nodes[node]
    return NominalMotion(
        robot=robot,
        path=(node,),
        controls=np.zeros((0, 2)),
        poses=np.array([[x, y, heading]]),
        node_steps=np.zeros(1, dtype=int),
        lm_visible=np.zeros((1, lib.world.landmark_xy.shape[0]), dtype=bool),
        noise_seed=0,
    )


@dataclass
class _Team:
    """Where the robots are and what they believe, between two plan steps."""

    names: list[str]
    node: dict[str, int]
    heading: dict[str, float]
    mean: np.ndarray  # (3N,) the team's joint belief
    cov: np.ndarray  # (3N, 3N)
    t: float = 0.0

    @staticmethod
    def at_start(lib: MotionLibrary, scenario: Scenario) -> _Team:
        names = [r.name for r in scenario.robots]
        cov = np.zeros((3 * len(names), 3 * len(names)))
        for i, r in enumerate(names):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = scenario.robot(r).cov
        return _Team(
            names,
            {r: lib.roadmap.starts[r] for r in names},
            {r: scenario.robot(r).pose.theta for r in names},
            np.concatenate([scenario.robot(r).pose.as_array() for r in names]),
            cov,
        )

    def request(self, moves: tuple[MoveKey, ...]) -> Request:
        """The oracle's request for the robots of ``moves`` from where they actually are,
        their joint covariance included when earlier steps correlated them."""
        robots = tuple(m[0] for m in moves)
        idx = [self.names.index(r) for r in robots]
        cols = np.concatenate([np.arange(3 * i, 3 * i + 3) for i in idx])
        sub_cov = self.cov[np.ix_(cols, cols)]
        starts = tuple(
            StartState(
                self.node[r],
                float(self.heading[r]),
                vec3(self.mean[3 * i : 3 * i + 3]),
                cov3(self.cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]),
            )
            for r, i in zip(robots, idx, strict=True)
        )
        correlated = len(robots) > 1 and bool(np.any(sub_cov[:3, 3:] != 0.0))
        joint = tuple(tuple(float(v) for v in row) for row in sub_cov) if correlated else None
        return Request(robots, starts, tuple(m[2] for m in moves), joint)

    def motions(self, lib: MotionLibrary, request: Request, result: MotionResult) -> list[NominalMotion]:
        """Every robot's motion during the step: the chosen one for the robots that move."""
        out = []
        for r in self.names:
            if r in request.robots:
                m = lib.motion(r, self.node[r], self.heading[r], result.goal_nodes[request.robots.index(r)])
                assert m is not None  # the oracle just planned it
                out.append(m)
            else:
                out.append(_stationary(lib, r, self.node[r], self.heading[r]))
        return out


def resimulate(
    lib: MotionLibrary,
    oracle: Oracle,
    scenario: Scenario,
    plan: list[tuple[MoveKey, ...]],
    planner_costs: list[float],
    action_names: list[str],
) -> Resimulation:
    """Run the plan's actions in order on the team's joint belief."""
    team = _Team.at_start(lib, scenario)
    dt = scenario.models.dt
    trajectories = {r: [_step(0.0, team.mean, team.cov, i, team.node[r])] for i, r in enumerate(team.names)}
    terms: dict[str, list[CostTerms]] = {r: [] for r in team.names}
    actions: list[PlannedAction] = []
    for k, moves in enumerate(plan):
        request = team.request(moves)
        robots = request.robots
        result = oracle.evaluate([request])[0]
        if result is None:
            raise TmpnavError(
                f"plan step {k + 1}: {', '.join(robots)} cannot reach {', '.join(request.rooms)} from where they are"
            )
        motions = team.motions(lib, request, result)
        idx = [team.names.index(r) for r in robots]
        h = max(m.n_steps for m in motions)
        mvis, mu_noise = _mutual(lib, motions, idx, robots, request.starts, h)
        run = trajectory(lib, motions, team.mean, team.cov, mvis, mu_noise)
        for i in idx:
            r, m = team.names[i], motions[i]
            reached = dict(zip(m.node_steps.tolist(), m.path, strict=False))
            for s in range(1, h + 1):
                trajectories[r].append(_step(team.t + s * dt, run.means[s], run.covs[s], i, reached.get(s)))
            terms[r].append(run.terms[i])
            team.node[r], team.heading[r] = m.path[-1], m.final_heading
        team.mean, team.cov = run.means[-1], run.covs[-1]
        actions.append(
            PlannedAction(
                index=k + 1,
                name=action_names[k],
                moves=tuple(moves),
                planner_cost=planner_costs[k],
                resimulated_cost=float(sum(run.terms[i].total(scenario.cost) for i in idx)),
                goal_nodes=result.goal_nodes,
                paths=tuple(motions[i].path for i in idx),
                goal_poses=tuple(vec3(motions[i].poses[-1]) for i in idx),
            )
        )
        team.t += h * dt
    return Resimulation(actions, trajectories, terms, Belief(team.mean, team.cov))


def _mutual(
    lib: MotionLibrary,
    motions: list[NominalMotion],
    idx: list[int],
    robots: tuple[str, ...],
    starts: tuple[StartState, ...],
    h: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Who sees whom among the moving robots, and the draws the oracle used for them."""
    N = len(motions)
    mvis = np.zeros((h + 1, N, N), dtype=bool)
    mu_noise = np.zeros((h + 1, N, N, 2))
    if len(idx) == 2:
        a, b = idx
        sensing = MutualSensing.between(lib.scenario, *robots)
        if sensing is not None:
            pa, pb = motions[a].padded(h)[1], motions[b].padded(h)[1]
            mvis[:, a, b] = sensing.visible(lib.world, pa, pb)
            mvis[:, b, a] = sensing.visible(lib.world, pb, pa)
        draws = np.random.default_rng(mutual_seed(lib, robots, starts)).standard_normal((h + 1, 2, 2, 2))
        mu_noise[:, a, b], mu_noise[:, b, a] = draws[:, 0, 1], draws[:, 1, 0]
    return mvis, mu_noise


def _step(t: float, mean: np.ndarray, cov: np.ndarray, i: int, node: int | None) -> TrajectoryStep:
    m = mean[3 * i : 3 * i + 3]
    c = cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]
    return TrajectoryStep(
        t=round(float(t), 9),
        mean=vec3(m),
        cov=cov3(c),
        node=None if node is None else int(node),
    )
