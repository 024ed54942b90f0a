"""Stage 6: the task stage's entry point, from a cost table to the ordered plan steps.

:func:`plan_task` owns everything between the oracle and the re-simulation: the lookup of
a remembered plan (:mod:`~tmpnav.task.memo`), encoding (:mod:`~tmpnav.task.encode`),
solving (:mod:`~tmpnav.task.solve`), decoding and ordering the plan's steps
(:mod:`~tmpnav.task.decode`) and their costs as the planner saw them. A new planner plugs
in behind :func:`~tmpnav.task.solve.solve` (registered in ``EXTRA_ENGINES``); one that
needs more than a PDDL problem (a search over sub-problems, a cost model that carries
beliefs) takes a :class:`TaskProblem` and returns a :class:`~tmpnav.results.TaskResult`,
like this function.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from tmpnav.errors import UnsolvableError
from tmpnav.results import BoundSummary, SearchSummary, StageTimes, TaskCounts, TaskResult
from tmpnav.task.bound import Bound
from tmpnav.task.decode import canonical_order, step_cost
from tmpnav.task.encode import EncodedTask, encode_task
from tmpnav.task.memo import EntryStore, Memo, entry_to_memo, memo_key, memo_to_entry
from tmpnav.task.model import CostModel
from tmpnav.task.modes import time_budget
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.search import Progress, SearchOptions, search
from tmpnav.task.unfolded import BeliefGraph, write_unfolded
from tmpnav.types import CostTable, Goals, PlannerOptions, PlanStatus, Scenario


@dataclass(frozen=True)
class TaskProblem:
    """What the task stage plans: the goals over the oracle's cost table, with the planner options."""

    table: CostTable
    goals: Goals
    planner: PlannerOptions  # engine, encoding, time limit, pair_min_gain
    name: str  # the scenario's name: the PDDL problem's name

    @classmethod
    def of(cls, scenario: Scenario, table: CostTable) -> TaskProblem:
        """The task problem of a scenario (its goals and planner options) over a cost table."""
        return cls(table, scenario.goals, scenario.planner, scenario.name)

    def encode(self) -> EncodedTask:
        """This task in the planner options' encoding, ready for the planner they name."""
        p = self.planner
        return encode_task(self.table, self.goals, p.encoding, p.name, name=self.name, min_gain=p.pair_min_gain)

    def memo_key(self) -> str:
        p = self.planner
        return memo_key(self.table, self.goals, p.encoding, p.pair_min_gain, p.name, self.name)


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
        return _result(task.table, memo, None)
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
        actions=solved.actions,
        steps=steps,
        sizes=(encoded.n_actions, len(encoded.pair_actions), len(encoded.potentials)),
    )
    if store is not None and key is not None:
        store.put_many({key: memo_to_entry(memo)})
    return _result(task.table, memo, encoded)


def encoded_problem(task: TaskProblem, result: TaskResult) -> EncodedTask:
    """The problem behind ``result``: the one solved, or encoded again after a remembered plan."""
    return result.encoded if result.encoded is not None else task.encode()


def _result(table: CostTable, memo: Memo, encoded: EncodedTask | None) -> TaskResult:
    """The memo's steps in canonical order, with their table costs."""
    order = canonical_order(list(memo.steps), table.robots)
    steps = tuple(memo.steps[i] for i in order)
    actions, pair_actions, reshaped = memo.sizes
    step_costs = tuple(step_cost(table, s) for s in steps)
    optimal = memo.status == PlanStatus.SOLVED_OPTIMALLY
    cost = float(sum(step_costs))
    return TaskResult(
        status=memo.status,
        engine=memo.engine,
        steps=steps,
        action_names=tuple(memo.actions[i][0] for i in order),
        step_costs=step_costs,
        counts=TaskCounts(len(table.single), len(table.pair), actions, pair_actions, reshaped),
        plan_hit=encoded is None,
        encoded=encoded,
        search=SearchSummary(mode="exact", costs="table", stopped="solved"),
        bound=BoundSummary(cost, "exact", 0.0, True) if optimal else None,
    )


#: neighbourhood sizes with carried costs: a sub-problem's first moves are costed from the
#: robots' beliefs at that point of the plan, its later ones from the beliefs the robot
#: would have after driving straight there, so small sub-problems spread over the plan
#: judge more of their moves in context (the landmark-sparse hall: (3, 4, 6) reached
#: 567.1, (4, 6, 8) 728.7, (6, 8) 1324.0; the corridor at 10 rooms: 7.9 s against 8.9 s)
CARRIED_SIZES = (3, 4, 6)


#: seconds of the run's budget kept for what runs after the search's budget is spent
BUDGET_MARGIN = 0.5


def plan_anytime(
    model: CostModel,
    goals: Goals,
    planner: PlannerOptions,
    bound: Callable[[], Bound] | None = None,
    times: StageTimes | None = None,
    progress: Progress | None = None,
    costs: str = "table",
    seeds: dict[str, Plan] | None = None,
    budget: float | None = None,
) -> TaskResult:
    """The anytime search's plan (:mod:`tmpnav.task.search`) on ``model``, with a certified
    lower bound on every plan's cost (``bound``, computed before the search starts).

    ``budget``: seconds for the search (default: ``planner.time_budget``, or by the
    problem's size (:func:`tmpnav.task.modes.time_budget`), less the time the
    run has spent so far, as ``times`` counts it, so the budget holds for the whole run)."""
    times = times if times is not None else StageTimes()
    proof = None
    if bound is not None:
        with times.timed("bound"):
            proof = bound()
    if budget is None:
        whole = time_budget(len(goals.all_rooms), len(model.robots), planner.time_budget)
        # leave time for what follows the search: its last sub-problem, the re-simulation
        budget = whole - sum(v for k, v in times.seconds.items() if k not in ("load", "total")) - BUDGET_MARGIN
    options = SearchOptions(
        planner=planner.name if planner.name.startswith("enhsp") else "enhsp-blind",
        encoding=planner.encoding if planner.encoding in ("single", "mixed") else "mixed",
        min_gain=planner.pair_min_gain,
        budget=max(budget, 0.0),
        sub_timeout=min(planner.timeout, 60.0),
        whole_is_exact=costs == "table",
        sizes=SearchOptions.sizes if costs == "table" else CARRIED_SIZES,
    )
    value = proof.value if proof is not None else None
    report = progress

    def noted(t: float, cost: float, _: float | None, what: str) -> None:
        if report is not None:
            report(t, cost, value, what)

    proves = proof.proves_optimal if proof is not None else None
    result = search(model, goals, options, noted, proves, seeds=seeds, times=times)
    plan, cost = result.plan, result.cost
    proved = result.stopped == "optimal"
    stats = result.stats
    return TaskResult(
        status=PlanStatus.SOLVED_OPTIMALLY if proved else PlanStatus.SOLVED_SATISFICING,
        engine=f"anytime search: OR-Tools start, {options.planner} on sub-problems",
        steps=plan,
        action_names=tuple("goto_room" if len(step) == 1 else "goto_room_pair" for step in plan),
        step_costs=cost.steps,
        counts=TaskCounts(0, 0, 0, sum(len(step) == 2 for step in plan), 0),
        plan_hit=False,
        search=SearchSummary(
            mode="anytime",
            costs=costs,
            stopped=result.stopped,
            start=result.start,
            subproblems=stats.subproblems,
            improvements=stats.improvements,
            seconds=stats.history[-1][0] if stats.history else 0.0,
            history=tuple(stats.history),
        ),
        bound=_summary(proof, cost.total, proved),
    )


def _summary(proof: Bound | None, cost: float, proved: bool) -> BoundSummary | None:
    """The bound as reported: ENHSP's own proof when its optimal search covered the whole
    problem, else the certified relaxation."""
    if proved and (proof is None or not proof.proves_optimal(cost)):
        return BoundSummary(cost, "exact (ENHSP's optimal search of the whole problem)", 0.0, True)
    return None if proof is None else BoundSummary(proof.value, proof.relaxation, proof.gap(cost), proved)


def plan_unfolded(
    graph: BeliefGraph,
    robots: tuple[str, ...],
    locations: tuple[str, ...],
    rules: Rules,
    planner: PlannerOptions,
    times: StageTimes | None = None,
) -> TaskResult:
    """ENHSP's optimal plan over an unfolded belief space (:mod:`tmpnav.task.unfolded`): the
    plan of least cost with carried-over beliefs."""
    times = times if times is not None else StageTimes()
    with times.timed("encode"):
        task = write_unfolded(graph, robots, locations, rules)
    engine = planner.name if planner.name.startswith("enhsp") else "enhsp-blind"
    with times.timed("planner"):
        solved = task.solve(engine, planner.timeout)
    edges = task.decode(solved)
    steps = tuple(e.step for e in edges)
    costs = tuple(e.cost for e in edges)
    optimal = solved.status == PlanStatus.SOLVED_OPTIMALLY
    total = float(sum(costs))
    return TaskResult(
        status=solved.status,
        engine=solved.engine,
        steps=steps,
        action_names=tuple("goto_room" if len(s) == 1 else "goto_room_pair" for s in steps),
        step_costs=costs,
        counts=TaskCounts(0, 0, len(graph.edges), sum(len(e.step) == 2 for e in graph.edges), 0),
        plan_hit=False,
        search=SearchSummary(
            mode="exact",
            costs="carried",
            stopped="solved",
            start=f"belief space unfolded: {graph.n_contexts} contexts, {len(graph.edges)} actions",
        ),
        bound=BoundSummary(total, "exact", 0.0, True) if optimal else None,
    )
