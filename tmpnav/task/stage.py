"""The task searches, each from its problem to a :class:`~tmpnav.results.TaskResult`.

* :func:`plan_task`, the exact search over a cost table: the lookup of a remembered plan
  (:mod:`~tmpnav.task.memo`), encoding (:mod:`~tmpnav.task.encode`), solving
  (:mod:`~tmpnav.task.solve`), decoding and ordering the plan's steps (:mod:`~tmpnav.task.decode`)
  and their costs as the planner saw them;
* :func:`plan_anytime`, the anytime search (:mod:`~tmpnav.task.search`) on a cost model;
* :func:`plan_unfolded`, ENHSP over an unfolded belief space (:mod:`~tmpnav.task.unfolded`).

They know tables, cost models and plans, never the oracle: :mod:`tmpnav.planning` runs them
for a run. A new PDDL engine plugs in behind :func:`~tmpnav.task.solve.solve` (registered in
``EXTRA_ENGINES``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from tmpnav.errors import UnsolvableError
from tmpnav.results import BoundSummary, Schedule, SearchSummary, StageTimes, TaskCounts, TaskResult
from tmpnav.task import solve
from tmpnav.task.bound import Bound
from tmpnav.task.budget import BOUND_CAP
from tmpnav.task.decode import canonical_order, step_cost
from tmpnav.task.encode import EncodedTask, encode_task
from tmpnav.task.export import pddl_texts
from tmpnav.task.memo import EntryStore, Memo, entry_to_memo, memo_key, memo_to_entry
from tmpnav.task.model import CostModel, entered, table_schedule
from tmpnav.task.objectives import OBJECTIVES
from tmpnav.task.pddl_text import DROP_PREFIX, TEXT_ENCODINGS, sample_task
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.schedules import exact_schedule
from tmpnav.task.search import search
from tmpnav.task.search_run import Executed, SearchOptions, SearchRun
from tmpnav.task.unfolded import BeliefGraph, write_unfolded
from tmpnav.types import CostTable, Goals, PlannerOptions, PlanStatus, Scenario


@dataclass(frozen=True)
class TaskProblem:
    """What the task stage plans: the goals over the oracle's cost table, with the planner options."""

    table: CostTable
    goals: Goals
    planner: PlannerOptions  # engine, encoding, time limit, pair_min_gain
    name: str  # the scenario's name: the PDDL problem's name
    span_weight: float = 0.0  # the objective's price of a second of makespan (tmpnav.task.objectives)

    @classmethod
    def of(cls, scenario: Scenario, table: CostTable) -> TaskProblem:
        """The task problem of a scenario (its goals, planner options and objective) over a cost table."""
        span = OBJECTIVES[scenario.planner.objective].span_weight(scenario.cost)
        return cls(table, scenario.goals, scenario.planner, scenario.name, span)

    def encode(self) -> EncodedTask:
        """This task in the planner options' encoding, ready for the planner they name."""
        p = self.planner
        return encode_task(
            self.table,
            self.goals,
            p.encoding,
            p.name,
            name=self.name,
            min_gain=p.pair_min_gain,
            span_weight=self.span_weight,
        )

    def memo_key(self, engine: str | None = None) -> str:
        """The key of this problem's remembered plan, solved by ``engine`` (the planner's by default)."""
        p = self.planner
        engine = p.name if engine is None else engine
        return memo_key(self.table, self.goals, p.encoding, p.pair_min_gain, engine, self.name, self.span_weight)


def plan_task(
    task: TaskProblem, store: EntryStore | None = None, replan: bool = False, times: StageTimes | None = None
) -> TaskResult:
    """The task plan, from ``store`` when it remembers this exact problem (unless ``replan``),
    else encoded and solved (and then remembered). ``times`` gets the ``encode`` and
    ``planner`` stages (a lookup counts as ``planner``). Raises a PlannerError when the
    planner fails."""
    times = times if times is not None else StageTimes()
    key, memo = None, None
    if store is not None:
        with times.timed("planner"):
            key = task.memo_key()
            found = None if replan else store.get_many([key]).get(key)
            memo = entry_to_memo(found, task.table) if found is not None else None
    if memo is not None:
        times.seconds.setdefault("encode", 0.0)
        return _result(task, memo, None)
    with times.timed("encode"):
        encoded = task.encode()
    with times.timed("planner"):
        solved = encoded.solve(task.planner.name, task.planner.timeout)
    steps = tuple(encoded.decode(solved))
    if any(len(step) == 2 and step not in task.table.pair and step[::-1] not in task.table.pair for step in steps):
        raise UnsolvableError(
            "no plan of the paper's encoding avoids a pair of moves the oracle cannot make "
            "(both robots would end on one pose instantiation): use --encoding mixed, or more roadmap.instantiations"
        )
    memo = Memo(
        status=solved.status,
        engine=solved.engine,
        actions=tuple(a for a in solved.actions if not a[0].lower().startswith(DROP_PREFIX)),  # one per step
        steps=steps,
        sizes=(encoded.n_actions, len(encoded.pair_actions), len(encoded.potentials)),
    )
    if store is not None and key is not None:
        store.put_many({key: memo_to_entry(memo)})
    return _result(task, memo, encoded)


#: the engine name that keys a remembered plan of the A* over schedules (not a PDDL planner)
SCHEDULES_ENGINE = "tmpnav A* over the schedules of the cost table"


def plan_schedules(
    task: TaskProblem, times: StageTimes | None = None, store: EntryStore | None = None, replan: bool = False
) -> TaskResult | None:
    """The exact plan of ``task`` when its objective prices time: the A* over every schedule of
    the table (:mod:`tmpnav.task.schedules`; ENHSP's optimal search does not cover a makespan).
    None when the problem is too large for it. ``times`` gets the ``planner`` stage.

    Like :func:`plan_task`, it is remembered in ``store`` (unless ``replan``): the plan, or that
    the problem is too large (so a warm run of a large one does not expand the A*'s states
    again before the anytime search takes over). The bound it reports is the plan's own
    objective, computed from its steps alike whether remembered or just found."""
    times = times if times is not None else StageTimes()
    key = None
    with times.timed("planner"):
        if store is not None:
            key = task.memo_key(SCHEDULES_ENGINE)
            entry = None if replan else store.get_many([key]).get(key)
            if isinstance(entry, dict) and entry.get("too_large") is True:
                return None
            memo = entry_to_memo(entry, task.table) if entry is not None else None
            if memo is not None:
                return _schedules_result(task, memo.steps, remembered=True)
        found = exact_schedule(task.table, task.goals, task.planner.pair_min_gain, task.span_weight)
    if found is None:
        if store is not None and key is not None:
            store.put_many({key: {"too_large": True}})
        return None
    steps = found[0]
    if store is not None and key is not None:
        actions = tuple((name, ()) for name in action_names(steps))
        memo = Memo(PlanStatus.SOLVED_OPTIMALLY, SCHEDULES_ENGINE, actions, steps, (0, 0, 0))
        store.put_many({key: memo_to_entry(memo)})
    return _schedules_result(task, steps, remembered=False)


def _schedules_result(task: TaskProblem, steps: Plan, remembered: bool) -> TaskResult:
    order = canonical_order(list(steps), task.table.robots)
    steps = tuple(steps[i] for i in order)
    step_costs = tuple(step_cost(task.table, s) for s in steps)
    schedule = table_schedule(task.table, steps, task.goals)
    value = _objective(task, steps, step_costs, schedule)
    return TaskResult(
        status=PlanStatus.SOLVED_OPTIMALLY,
        engine=SCHEDULES_ENGINE,
        steps=steps,
        action_names=action_names(steps),
        step_costs=step_costs,
        counts=TaskCounts(len(task.table.single), len(task.table.pair), 0, sum(len(s) == 2 for s in steps), 0),
        plan_hit=remembered,
        search=SearchSummary(mode="exact", costs="table", stopped="solved"),
        bound=BoundSummary(value, "exact (A* over every schedule)", 0.0, True),
        schedule=schedule,
    )


def _objective(task: TaskProblem, steps: Plan, step_costs: tuple[float, ...], schedule: Schedule | None) -> float:
    """The plan's objective on the table: its steps' costs plus the price of its makespan (and
    of the optional goals it leaves undone)."""
    dropped = task.goals.drop_penalty(entered(steps, task.table.start_location))
    return float(sum(step_costs)) + dropped + task.span_weight * (schedule.makespan if schedule is not None else 0.0)


def _result(task: TaskProblem, memo: Memo, encoded: EncodedTask | None) -> TaskResult:
    """The memo's steps in canonical order, with their table costs and schedule."""
    table = task.table
    order = canonical_order(list(memo.steps), table.robots)
    steps = tuple(memo.steps[i] for i in order)
    actions, pair_actions, reshaped = memo.sizes
    step_costs = tuple(step_cost(table, s) for s in steps)
    optimal = memo.status == PlanStatus.SOLVED_OPTIMALLY
    schedule = table_schedule(table, steps, task.goals)
    cost = _objective(task, steps, step_costs, schedule)
    return TaskResult(
        status=memo.status,
        engine=memo.engine,
        steps=steps,
        action_names=tuple(memo.actions[i][0] for i in order),
        step_costs=step_costs,
        counts=TaskCounts(len(table.single), len(table.pair), actions, pair_actions, reshaped),
        plan_hit=encoded is None,
        search=SearchSummary(mode="exact", costs="table", stopped="solved"),
        bound=BoundSummary(cost, "exact", 0.0, True) if optimal else None,
        schedule=schedule,
        pddl=None if encoded is None else lambda: pddl_texts(encoded),
    )


#: neighbourhood sizes with carried costs: a sub-problem's first moves are costed from the
#: robots' beliefs at that point of the plan, its later ones from the beliefs the robot
#: would have after driving straight there, so small sub-problems spread over the plan
#: judge more of their moves in context (the landmark-sparse hall: (3, 4, 6) reached
#: 567.1, (4, 6, 8) 728.7, (6, 8) 1324.0; the corridor at 10 rooms: 7.9 s against 8.9 s)
CARRIED_SIZES = (3, 4, 6)


@dataclass(frozen=True)
class AnytimeTask:
    """What the anytime search plans: the goals on a cost model, with the planner options."""

    model: CostModel
    goals: Goals
    planner: PlannerOptions  # engine (an ENHSP one), encoding (single or mixed), time limit, pair_min_gain
    span_weight: float = 0.0  # the objective's price of a second of makespan (tmpnav.task.objectives)
    #: a plan's cost as it will be executed (robots kept apart); None: as planned
    executed: Executed | None = None
    #: OR-Tools' routes as a first plan (SearchOptions.first_routes)
    first_routes: bool = True

    def options(self, budget: float, work: int | None = None) -> SearchOptions:
        """The search's options (``budget``: its time cap in seconds; ``work``: its budget in
        sub-problems): with costs that depend on the context (carried beliefs), smaller
        neighbourhoods, and no proof of optimality from one search of the whole problem."""
        p, context_free = self.planner, self.model.costs == "table"
        return SearchOptions(
            planner=p.name,
            encoding=p.encoding,
            min_gain=p.pair_min_gain,
            budget=max(budget, 0.0),
            work=work,
            sub_timeout=min(p.timeout, 60.0),
            whole_is_exact=context_free,
            sizes=SearchOptions.sizes if context_free else CARRIED_SIZES,
            span_weight=self.span_weight,
            first_routes=self.first_routes,
            routing_time=p.routing_time,
            min_rooms=p.min_rooms,
        )


def warm_up(task: AnytimeTask) -> None:
    """Get ENHSP ready for the anytime search's sub-problems while the run computes its first
    costs and plan (:func:`warm_up_searches`); nothing when they are ready already."""
    opts = task.options(0.0)
    warm_up_searches(opts.planner, opts.encoding, opts.span_weight, opts.min_gain)


def warm_up_searches(planner: str, encoding: str, span_weight: float, min_gain: float) -> None:
    """ENHSP's server started, and one search ready in it for each sub-problem the anytime
    search solves at once, warmed on a small problem of the search's encoding and objective
    (:func:`tmpnav.task.solve.warm_up`): in the background, while the caller goes on."""
    if encoding not in TEXT_ENCODINGS:
        return
    sample = sample_task(encoding, span_weight, min_gain)
    solve.warm_up(planner, SearchOptions.parallel, sample.domain, sample.problem)


class PendingBound(Protocol):
    """A lower bound computed beside the search: started once the single moves are costed, and
    given (waited for) when first asked (tmpnav.planning.bound.LaterBound)."""

    def start(self) -> None: ...

    def __call__(self) -> Bound: ...


def plan_anytime(
    task: AnytimeTask,
    run: SearchRun,
    budget: float,
    bound: Bound | PendingBound | None = None,
    seeds: dict[str, Plan] | None = None,
    work: int | None = None,
) -> TaskResult:
    """The anytime search's plan (:mod:`tmpnav.task.search`) of ``task`` within ``work``
    sub-problems and a time cap of ``budget`` seconds, from the cheapest of OR-Tools' routes and
    the ``seeds``; ``bound``, a certified lower bound on every plan's cost (or one computed beside
    the search from when the single moves are costed), can prove a plan optimal and gives the gap."""
    later = _later(bound)
    proves = None if later is None else (lambda cost: later().proves_optimal(cost))
    told = None if later is None else (lambda: later().value)
    costed = None if bound is None or isinstance(bound, Bound) else bound.start
    options = task.options(budget, work)
    result = search(task.model, task.goals, options, run.bounded(told, costed), proves, seeds, task.executed)
    found = None if later is None else later()
    plan, cost = result.plan, result.cost
    proved = result.stopped == "optimal"
    stats = result.stats
    return TaskResult(
        status=PlanStatus.SOLVED_OPTIMALLY if proved else PlanStatus.SOLVED_SATISFICING,
        engine=f"anytime search: OR-Tools start, {task.planner.name} on sub-problems",
        steps=plan,
        action_names=action_names(plan),
        step_costs=cost.steps,
        counts=TaskCounts(0, 0, 0, sum(len(step) == 2 for step in plan), 0),
        plan_hit=False,
        search=SearchSummary(
            mode="anytime",
            costs=task.model.costs,
            stopped=result.stopped,
            start=result.start,
            subproblems=stats.subproblems,
            improvements=stats.improvements,
            seconds=stats.history[-1][0] if stats.history else 0.0,
            history=tuple(stats.history),
            work=options.work,
            # a bound its time share cut short stops the search later, or not at all: the plan is the machine's
            capped=(*result.capped, *((BOUND_CAP,) if found is not None and found.stopped else ())),
        ),
        bound=_summary(found, cost.value(task.span_weight), proved),
        schedule=cost.schedule,
    )


def _later(bound: Bound | PendingBound | None) -> Callable[[], Bound] | None:
    """What gives the bound when asked: ``bound`` itself when computed already."""
    if isinstance(bound, Bound):
        return lambda: bound
    return bound


def action_names(plan: Plan) -> tuple[str, ...]:
    """The domain's action of each step: ``goto_room`` for one robot, ``goto_room_pair`` for two."""
    return tuple("goto_room" if len(step) == 1 else "goto_room_pair" for step in plan)


def _summary(proof: Bound | None, cost: float, proved: bool) -> BoundSummary | None:
    """The bound as reported: ENHSP's own proof when its optimal search covered the whole
    problem, else the certified relaxation."""
    if proved and (proof is None or not proof.proves_optimal(cost)):
        return BoundSummary(cost, "exact (ENHSP's optimal search of the whole problem)", 0.0, True)
    return None if proof is None else BoundSummary(proof.value, proof.relaxation, proof.gap(cost), proved)


def plan_unfolded(
    graph: BeliefGraph,
    model: CostModel,
    rules: Rules,
    planner: PlannerOptions,
    run: SearchRun,
    span_weight: float = 0.0,
) -> TaskResult:
    """ENHSP's optimal plan over an unfolded belief space (:mod:`tmpnav.task.unfolded`): the
    plan of least objective with carried-over beliefs, the team moving at once. Its steps'
    costs and its schedule are the model's (the edges price time windows, not steps)."""
    robots = tuple(rules.start_location)
    locations = tuple(dict.fromkeys([*rules.goals.all_rooms, *rules.start_location.values()]))
    with run.times.timed("encode"):
        task = write_unfolded(graph, robots, locations, rules)
    with run.times.timed("planner"):
        solved = task.solve(planner.name, planner.timeout)
    steps = tuple(e.step for e in task.decode(solved) if e.step)
    with run.times.timed("oracle"):
        cost = model.plan_cost(steps)
    optimal = solved.status == PlanStatus.SOLVED_OPTIMALLY
    return TaskResult(
        status=solved.status,
        engine=solved.engine,
        steps=steps,
        action_names=action_names(steps),
        step_costs=cost.steps,
        counts=TaskCounts(0, 0, len(graph.edges), sum(len(e.step) == 2 for e in graph.edges), 0),
        plan_hit=False,
        search=SearchSummary(
            mode="exact",
            costs="carried",
            stopped="solved",
            start=f"belief space unfolded on the team's clock: {graph.n_contexts} contexts, {len(graph.edges)} actions",
        ),
        bound=BoundSummary(cost.value(span_weight), "exact", 0.0, True) if optimal else None,
        schedule=cost.schedule,
    )
