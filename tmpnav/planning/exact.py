"""The exact search with table costs: every cost the encoding may need first, then one optimal
ENHSP search over the whole table (the paper's pipeline; :func:`tmpnav.task.stage.plan_task`)."""

from __future__ import annotations

from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import build_table, start_locations
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.results import StageTimes
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.stage import TaskProblem, plan_task
from tmpnav.types import CostTable, Scenario
from tmpnav.world import World


def exact_table(run: TaskRun) -> Planned:
    """The table of every move and paired move the encoding asks for, and ENHSP's optimal plan on it."""
    table = full_table(run.scenario, run.world, run.canonical.oracle, run.times)
    return Planned(table, plan_task(TaskProblem.of(run.scenario, table), run.store, run.replan, run.times))


def full_table(scenario: Scenario, world: World, oracle: Oracle, times: StageTimes) -> CostTable:
    """Every cost the encoding may need, before the exact planner runs (stage ``oracle``)."""
    with times.timed("oracle"):
        sp = scenario.planner
        want = ENCODINGS[sp.encoding].table_request(scenario.goals, start_locations(scenario, world), sp.pair_min_gain)
        return build_table(
            oracle,
            world,
            want.destinations,
            want.pair_filter,
            filter_key=want.filter_key,
            pair_min_gain=want.pair_min_gain,
        )
