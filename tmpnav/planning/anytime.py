"""The anytime search of a run (:mod:`tmpnav.task.search`): on table costs computed as it asks
for them, or on carried costs."""

from __future__ import annotations

from tmpnav.attachment.apart import ExecutedCost
from tmpnav.choices import exact_fits
from tmpnav.planning.bound import LaterBound, certified_bound
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.planning.table import full_table
from tmpnav.task.bound import Bound
from tmpnav.task.plans import Plan, Rules, with_origins, without_revisits
from tmpnav.task.search import UNDER_WAY
from tmpnav.task.stage import AnytimeTask, TaskProblem, plan_anytime, plan_task, warm_up

#: seconds of the run's budget kept for what runs after the search's budget is spent (its last
#: sub-problem, the re-simulation)
BUDGET_MARGIN = 0.5


def anytime_table(run: TaskRun) -> Planned:
    """The anytime search on table costs, with the certified lower bound of the table."""
    anytime = AnytimeTask(run.canonical, run.goals, run.planner, run.span_weight)
    _warm_up(run, anytime)
    bound = _bound(run)
    task = plan_anytime(anytime, run.search, _left(run), bound, _incumbent(run), run.work)
    return Planned(run.canonical.seen(), task)


def _incumbent(run: TaskRun) -> dict[str, Plan]:
    """The plan being executed, revised, as a seed of the search (none when the run has none;
    the search drops a seed its rules refuse)."""
    if not run.incumbent:
        return {}
    start = run.canonical.start_location
    return {UNDER_WAY: with_origins(without_revisits(run.incumbent, Rules(start, run.goals)), start)}


def anytime_carried(
    run: TaskRun,
    seeds: dict[str, Plan] | None = None,
    floor: Bound | None = None,
    executed: ExecutedCost | None = None,
) -> Planned:
    """The anytime search with carried costs, every plan costed as executed, from the cheapest
    of OR-Tools' routes, the plan being executed (a replan's) or else (where quick) the exact
    plan of the cost table.

    It used to search with table costs first, for up to half the budget, and seed the carried
    search with that plan. On every case of benchmarks/bench_converge.py that phase improved
    nothing the carried search did not find (the corridor's 10 rooms: the same plan, 5.4 s
    instead of 9.6 s; the 20-room building and the landmark-sparse hall: the same plans; 40
    rooms and 4 robots: 2081.0 instead of 2281.1 at the budget, the carried search having the
    time), so the whole budget goes to the costs the plan is judged by. A plan is judged as it
    will be executed: with its robots kept apart (waits, detours, sidesteps) when the scenario
    keeps them apart. ``seeds`` (name -> plan), when given, take the place of the exact plan of
    the cost table, and ``floor`` the certified bound: the unfolded search's plan that keeping
    robots apart made dearer, and its cost as planned, the least of every plan as planned
    (tmpnav.planning.unfolded); ``executed``, the pricing that found it dearer (:func:`executed_cost`,
    which remembers that plan's price)."""
    # an exact plan as a seed is no worse as planned than OR-Tools' routes of single moves
    routes = not seeds
    executed = executed if executed is not None else executed_cost(run)
    anytime = AnytimeTask(run.carried, run.goals, run.planner, run.span_weight, executed, routes)
    _warm_up(run, anytime)
    seeds = {**_incumbent(run), **(seeds or {})}
    # the bound: computed beside the first routes and plans (its motion floors need no oracle)
    bound = floor if floor is not None else LaterBound(run)
    # a replan starts from its incumbent: the exact search of the table is not budgeted (3-6 s
    # for 3 rooms and 4 robots, against a replan's 1-2 s)
    if not seeds and exact_fits(len(run.goals.all_rooms), len(run.scenario.robots), "table"):
        table = full_table(run.scenario, run.world, run.canonical.oracle, run.times, run.canonical.origin)
        exact = plan_task(TaskProblem.of(run.scenario, table), run.store, run.replan, run.times)
        seeds["the exact plan of the cost table"] = exact.steps
    task = plan_anytime(anytime, run.search, _left(run), bound, seeds, run.work)
    return Planned(run.canonical.seen(), task)


def executed_cost(run: TaskRun) -> ExecutedCost | None:
    """Every plan the search would take priced as ``tmpnav plan`` will execute it, robots kept
    apart (planner.keep_apart), so that the plan it picks is the plan executed."""
    planner = run.scenario.planner
    return ExecutedCost(run.carried, planner.max_risk) if planner.keep_apart else None


def _warm_up(run: TaskRun, anytime: AnytimeTask) -> None:
    """ENHSP's JVM started now (the planner's time) and its searches made ready in the background
    while the first costs, plan and bound are computed (tmpnav.task.stage.warm_up)."""
    with run.times.timed("planner"):
        warm_up(anytime)


def _bound(run: TaskRun) -> Bound:
    with run.times.timed("bound"):
        return certified_bound(run)


def _left(run: TaskRun) -> float:
    """The search's budget: the run's, less what its stages spent and :data:`BUDGET_MARGIN`."""
    return max(run.left() - BUDGET_MARGIN, 0.0)
