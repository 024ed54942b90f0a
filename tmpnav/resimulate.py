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
from tmpnav.types import Belief, CostTerms, MoveKey, PlannedAction, Scenario, TrajectoryStep, cov3, vec3


@dataclass
class Resimulation:
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


def resimulate(
    lib: MotionLibrary,
    oracle: Oracle,
    scenario: Scenario,
    plan: list[tuple[MoveKey, ...]],
    planner_costs: list[float],
    action_names: list[str],
) -> Resimulation:
    """Run the plan's actions in order on the team's joint belief."""
    names = [r.name for r in scenario.robots]
    N = len(names)
    node = {r: lib.roadmap.starts[r] for r in names}
    heading = {r: scenario.robot(r).pose.theta for r in names}
    mean = np.concatenate([scenario.robot(r).pose.as_array() for r in names])
    cov = np.zeros((3 * N, 3 * N))
    for i, r in enumerate(names):
        cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = scenario.robot(r).cov
    t = 0.0
    dt = scenario.models.dt
    trajectories = {r: [_step(t, mean, cov, i, node[r])] for i, r in enumerate(names)}
    terms: dict[str, list[CostTerms]] = {r: [] for r in names}
    actions: list[PlannedAction] = []
    for k, moves in enumerate(plan):
        robots = tuple(m[0] for m in moves)
        idx = [names.index(r) for r in robots]
        cols = np.concatenate([np.arange(3 * i, 3 * i + 3) for i in idx])
        sub_cov = cov[np.ix_(cols, cols)]
        starts = tuple(
            StartState(
                node[r],
                float(heading[r]),
                vec3(mean[3 * i : 3 * i + 3]),
                cov3(cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]),
            )
            for r, i in zip(robots, idx, strict=True)
        )
        correlated = len(robots) > 1 and bool(np.any(sub_cov[:3, 3:] != 0.0))
        request = Request(
            robots,
            starts,
            tuple(m[2] for m in moves),
            tuple(tuple(float(v) for v in row) for row in sub_cov) if correlated else None,
        )
        result = oracle.evaluate([request])[0]
        if result is None:
            raise TmpnavError(
                f"plan step {k + 1}: {', '.join(robots)} cannot reach {', '.join(request.rooms)} from where they are"
            )
        motions = []
        for r in names:
            if r in robots:
                j = robots.index(r)
                m = lib.motion(r, node[r], heading[r], result.goal_nodes[j])
                assert m is not None
                motions.append(m)
            else:
                motions.append(_stationary(lib, r, node[r], heading[r]))
        h = max(m.n_steps for m in motions)
        mvis, mu_noise = _mutual(lib, motions, idx, robots, starts, h)
        run = trajectory(lib, motions, mean, cov, mvis, mu_noise)
        for i, r in enumerate(names):
            if r not in robots:
                continue
            m = motions[i]
            reached = dict(zip(m.node_steps.tolist(), m.path, strict=False))
            for s in range(1, h + 1):
                trajectories[r].append(_step(t + s * dt, run.means[s], run.covs[s], i, reached.get(s)))
            terms[r].append(run.terms[i])
            node[r] = m.path[-1]
            heading[r] = m.final_heading
        mean, cov = run.means[-1], run.covs[-1]
        cost = float(sum(run.terms[i].total(scenario.cost) for i in idx))
        actions.append(
            PlannedAction(
                index=k + 1,
                name=action_names[k],
                moves=tuple(moves),
                planner_cost=planner_costs[k],
                resimulated_cost=cost,
                goal_nodes=result.goal_nodes,
                paths=tuple(motions[i].path for i in idx),
                goal_poses=tuple(
                    (float(motions[i].poses[-1, 0]), float(motions[i].poses[-1, 1]), float(motions[i].poses[-1, 2]))
                    for i in idx
                ),
            )
        )
        t += h * dt
    return Resimulation(actions, trajectories, terms, Belief(mean, cov))


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
        pa, pb = motions[a].padded(h)[1], motions[b].padded(h)[1]
        radius = sum(lib.scenario.robot(r).radius for r in robots)
        mvis[:, a, b] = lib.mutual_visibility_pairs(pa, pb, radius)
        mvis[:, b, a] = lib.mutual_visibility_pairs(pb, pa, radius)
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
