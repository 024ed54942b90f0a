"""Stage 7: the task-motion plan, re-simulated with beliefs carried from action to action.

The plan's actions run in order from the robots' true situation: each action starts where
its robots actually are, with their actual beliefs, cross-correlations included, and the
oracle picks its goal instantiations again from there (paper: "this instantiation becomes
the start node" of the next move). The whole team is one joint EKF state: robots that do
not move in an action stay still, neither observe nor are observed, and their beliefs
change only through their correlations with the robots that move. The steps are
:meth:`tmpnav.attachment.carried.CarriedCosts.replay`, the same code that costs plans for
the planner with ``--costs carried``, recording every control step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.team import Team, belief_step
from tmpnav.results import TaskResult
from tmpnav.types import Belief, CostTerms, PlannedAction, TrajectoryStep


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


def resimulate(carried: CarriedCosts, task: TaskResult) -> Resimulation:
    """Run the task plan's actions in order on the team's joint belief."""
    team: Team = carried.start
    trajectories = {r: [belief_step(0.0, team.mean, team.cov, i, team.node[i])] for i, r in enumerate(team.names)}
    terms: dict[str, list[CostTerms]] = {r: [] for r in team.names}
    actions: list[PlannedAction] = []
    outcomes = carried.replay(task.steps)
    for k, (moves, outcome) in enumerate(zip(task.steps, outcomes, strict=True)):
        assert outcome.trajectories is not None
        for r, steps in outcome.trajectories.items():
            trajectories[r].extend(steps)
        for r, t in zip(outcome.robots, outcome.terms, strict=True):
            terms[r].append(t)
        actions.append(
            PlannedAction(
                index=k + 1,
                name=task.action_names[k],
                moves=tuple(moves),
                planner_cost=task.step_costs[k],
                resimulated_cost=outcome.cost,
                goal_nodes=outcome.goal_nodes,
                paths=outcome.paths,
                goal_poses=outcome.goal_poses,
            )
        )
        team = outcome.team
    return Resimulation(actions, trajectories, terms, Belief(team.mean, team.cov))
