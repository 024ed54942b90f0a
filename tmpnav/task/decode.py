"""Stage 6c: a plan from the planner -> the ordered task actions as robot moves."""

from __future__ import annotations

from tmpnav.errors import PlannerCrashError
from tmpnav.task.encode import EncodedProblem
from tmpnav.task.solve import SolveResult
from tmpnav.types import CostTable, MoveKey


def decode(result: SolveResult, encoded: EncodedProblem) -> list[tuple[MoveKey, ...]]:
    """The plan's actions, each as the moves of the robots it moves (1 or 2)."""
    steps: list[tuple[MoveKey, ...]] = []
    for name, params in result.actions:
        if name in encoded.pair_actions:
            steps.append(encoded.pair_actions[name])
        elif name == "goto_room" and len(params) == 3:
            steps.append(((params[0], params[1], params[2]),))
        elif name == "goto_room" and len(params) == 6:
            steps.append(((params[0], params[1], params[2]), (params[3], params[4], params[5])))
        else:
            raise PlannerCrashError(f"the planner returned an action tmpnav does not know: {name}{params}")
    return steps


def step_cost(table: CostTable, step: tuple[MoveKey, ...]) -> float:
    """The table cost of one plan step, as the planner saw it (before reshaping)."""
    if len(step) == 1:
        return table.single[step[0]]
    m1, m2 = step
    return table.pair[(m1, m2)] if (m1, m2) in table.pair else table.pair[(m2, m1)]
