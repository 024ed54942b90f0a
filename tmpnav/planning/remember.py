"""Plans of the anytime and the unfolded search, remembered like the exact planner's.

Both searches are deterministic: OR-Tools stops after a fixed number of solutions, the
neighbourhoods come from a seeded generator, the anytime search's budget is a count of
sub-problems (tmpnav.task.budget), ENHSP and the oracle give the same answers to the same
questions. So a run whose inputs are identical to an earlier one reads its plan instead of
searching again. A plan is remembered with the search's work budget: unless it was proved
optimal, or converged within fewer sub-problems than a run's budget, it is read again only
by a run of the same work budget. A plan a time cap cut short (the search's, OR-Tools', a
sub-problem's) depends on the machine's speed, and is not remembered.

The key covers the oracle's context (its code, the world, the roadmap, the models and
weights), the robots, the goals, the planner options that shape the search (engine,
encoding, pair_min_gain, search, costs), the objective (and its price of time, the chance
constraint, whether robots are kept apart and with what clock drift, which the search
prices) and the code
of the task stage (task/, attachment/, planning/). On
a hit the plan's costs are computed again by the cost model (from the oracle's cache: the
same numbers), so a remembered plan is reported exactly as a searched one.
"""

from __future__ import annotations

import hashlib
import math
from functools import lru_cache

from tmpnav.attachment.drift import clock_drift
from tmpnav.digest import folders_digest
from tmpnav.results import JSON, BoundSummary, SearchSummary, TaskCounts, TaskResult
from tmpnav.task.memo import EntryStore
from tmpnav.task.model import CostModel
from tmpnav.task.plans import Rules
from tmpnav.types import Goals, MoveKey, PlanStatus, Scenario

VERSION = "search-plan/3"
#: a search that ended like this gives the same plan under any budget
FINAL = ("optimal", "solved", "nothing to do")


@lru_cache(maxsize=1)
def _code_version() -> str:
    return folders_digest(("task", "attachment", "planning"))


def search_key(scenario: Scenario, context: str) -> str:
    """The key of a search: see the module docstring."""
    sp = scenario.planner
    robots = [(r.name, r.pose, r.covariance, r.radius, r.speed, r.turn_rate) for r in scenario.robots]
    parts = (VERSION, _code_version(), context, robots, scenario.goals, sp.name, sp.encoding, repr(sp.pair_min_gain))
    # what the plan minimises, within what, and whether it is judged with its robots kept apart
    time: tuple[object, ...] = (sp.objective, repr(scenario.cost.M_T), repr(sp.max_risk), sp.keep_apart)
    time += (repr(clock_drift(scenario)),) + ((sp.min_rooms,) if sp.min_rooms else ())  # no minimum: keys as before
    return hashlib.sha256(repr((*parts, sp.search, sp.costs, *time)).encode()).hexdigest()


def remember(store: EntryStore, key: str, task: TaskResult, work: int) -> None:
    """Store ``task``, found within a work budget of ``work`` sub-problems, unless a time cap
    cut its search short."""
    s = task.search
    if s is None or s.capped:
        return
    entry: JSON = {
        "work": work,
        "status": task.status.value,
        "engine": task.engine,
        "steps": [[list(m) for m in step] for step in task.steps],
        "names": list(task.action_names),
        "search": s.to_json(),
        "bound": None
        if task.bound is None
        else {"value": task.bound.value, "relaxation": task.bound.relaxation, "proved": task.bound.proved_optimal},
    }
    store.put_many({key: entry})


def recall(
    store: EntryStore, key: str, model: CostModel, goals: Goals, work: int, span_weight: float = 0.0
) -> TaskResult | None:
    """The remembered result, its costs and schedule from ``model`` (its gap on the objective of
    ``span_weight``); None on a miss, on an entry that is damaged or is not a plan of these
    goals, or on a plan that a run of ``work`` sub-problems may not find (see the module docstring)."""
    entry = store.get_many([key]).get(key)
    if not isinstance(entry, dict):
        return None
    try:
        stopped, solved, given = entry["search"]["stopped"], entry["search"]["subproblems"], entry["work"]
        converged = stopped == "converged" and work > int(solved)
        if stopped not in FINAL and not converged and work != int(given):
            return None
        steps: tuple[tuple[MoveKey, ...], ...] = tuple(
            tuple((str(m[0]), str(m[1]), str(m[2])) for m in step) for step in entry["steps"]
        )
        if not isinstance(entry["search"], dict):
            return None
        search = SearchSummary.from_json(entry["search"])
        b = entry["bound"]
        status = PlanStatus(entry["status"])
        names = tuple(str(n) for n in entry["names"])
        engine = str(entry["engine"])
        bound_value = None if b is None else (float(b["value"]), str(b["relaxation"]), bool(b["proved"]))
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    shapes = all(1 <= len(step) <= 2 and all(len(m) == 3 for m in step) for step in steps)
    if not shapes or not {m[0] for step in steps for m in step} <= set(model.robots):
        return None
    if not Rules(model.start_location, goals).valid(steps):
        return None
    cost = model.plan_cost(steps)
    if not math.isfinite(cost.total):
        return None
    bound = None
    if bound_value is not None:
        value, relaxation, proved = bound_value
        objective = cost.value(span_weight)
        gap = max(0.0, (objective - value) / objective) if objective > 0 else 0.0
        bound = BoundSummary(value, relaxation, gap, proved)
    counts = TaskCounts(0, 0, 0, sum(len(x) == 2 for x in steps), 0)
    return TaskResult(status, engine, steps, names, cost.steps, counts, True, search, bound, cost.schedule)
