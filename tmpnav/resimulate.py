"""Stage 7: the task-motion plan, re-simulated as the team runs it: all robots at once, on one clock.

The plan's moves run from the robots' true situation (:meth:`CarriedCosts.replay`, the team's
clock of :mod:`tmpnav.attachment.clock`): each robot makes its moves one after another, a
paired move starts when both of its robots are free, and every move starts where its robot
actually is, with its actual belief, cross-correlations included; the oracle picks its goal
instantiation again from there (paper: "this instantiation becomes the start node" of the
next move). The whole team is one joint EKF: standing robots keep observing and being
observed, and any two robots in range and line of sight observe each other. It is the same
run that costs plans for the planner with ``--costs carried``, recording every control step.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from tmpnav.attachment.carried import CarriedCosts
from tmpnav.oracle.nominal import NominalMotion
from tmpnav.results import Schedule, TaskResult
from tmpnav.types import Belief, CostTerms, PlannedAction, TrajectoryStep


@dataclass
class Resimulation:
    """The plan re-simulated: its actions with their costs, each robot's belief at every
    step, each robot's cost terms per move, its schedule and the team's joint belief at the end."""

    actions: list[PlannedAction]
    trajectories: dict[str, list[TrajectoryStep]]
    schedule: Schedule
    terms: dict[str, list[CostTerms]] = field(default_factory=dict)
    final: Belief | None = None

    @property
    def cost(self) -> float:
        return sum(a.resimulated_cost for a in self.actions)


def resimulate(
    carried: CarriedCosts,
    task: TaskResult,
    delays: Mapping[int, float] | None = None,
    detours: Mapping[tuple[int, str], tuple[int, ...]] | None = None,
) -> Resimulation:
    """Run the task plan on the team's clock (``delays`` hold steps back, in seconds;
    ``detours`` drive moves along other roadmap paths, ``TeamClock.run``)."""
    names, weights = carried.start.names, carried.scenario.cost
    run = carried.replay(task.steps, delays, detours)
    terms: dict[str, list[CostTerms]] = {r: [] for r in names}
    by_step: dict[int, list] = {}
    for move in run.moves:
        by_step.setdefault(move.step, []).append(move)
    actions = []
    for k, moves in enumerate(task.steps):
        ran = sorted(by_step[k], key=lambda m: [x[0] for x in moves].index(names[m.robot]))
        for m in ran:
            assert m.terms is not None
            terms[names[m.robot]].append(m.terms)
        actions.append(
            PlannedAction(
                index=k + 1,
                name=task.action_names[k],
                moves=tuple(moves),
                planner_cost=task.step_costs[k],
                resimulated_cost=float(sum(m.cost(weights) for m in ran)),
                goal_nodes=tuple(int(m.motion.path[-1]) for m in ran),
                paths=tuple(m.motion.path for m in ran),
                goal_poses=tuple(_goal_pose(carried, m.motion) for m in ran),
                risk=tuple(m.risk for m in ran),
                controllers=tuple(m.motion.controller for m in ran),
            )
        )
    assert run.trajectories is not None
    team = run.end.team
    return Resimulation(actions, run.trajectories, run.schedule, terms, Belief(team.mean, team.cov))


def _goal_pose(carried: CarriedCosts, motion: NominalMotion) -> tuple[float, float, float]:
    """Where a move is sent: its goal node's position, with a job's station heading there or the
    heading the motion ends with. A move driven turn-then-drive ends on it; one driven by RPP
    stops within nav2's goal tolerance of it, as nav2 does of the goal it is given
    (docs/models.md)."""
    node = motion.path[-1]
    x, y = (float(v) for v in carried.lib.roadmap.nodes[node, :2])
    heading = carried.lib.goal_headings.get(node)
    return (x, y, motion.final_heading if heading is None else float(heading))
