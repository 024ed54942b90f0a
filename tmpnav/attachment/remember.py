"""Plans of the anytime and the unfolded search, remembered like the exact planner's.

Both searches are deterministic: OR-Tools stops after a fixed number of solutions, the
neighbourhoods come from a seeded generator, ENHSP and the oracle give the same answers to
the same questions. So a run whose inputs are identical to an earlier one reads its plan
instead of searching again. A plan is remembered with the run's time budget: unless it was
proved optimal, it may depend on that budget (a search cut short by it, or a first phase
cut short, depends on the machine's speed too), so it is read again only by a run whose
budget is no larger -- the same run repeated gives the same plan at once, a larger budget
searches again.

The key covers the oracle's context (its code, the world, the roadmap, the models and
weights), the robots, the goals, the planner options that shape the search (engine,
encoding, pair_min_gain, search, costs) and the code of the task and attachment stages. On
a hit the plan's costs are computed again by the cost model (from the oracle's cache: the
same numbers), so a remembered plan is reported exactly as a searched one.
"""

from __future__ import annotations

import hashlib
import math
from functools import lru_cache
from pathlib import Path

from tmpnav.results import JSON, BoundSummary, SearchSummary, TaskCounts, TaskResult
from tmpnav.task.memo import EntryStore
from tmpnav.task.model import CostModel
from tmpnav.task.plans import Rules
from tmpnav.types import Goals, MoveKey, PlanStatus, Scenario

VERSION = "search-plan/2"
#: a search that ended like this gives the same plan under any budget
FINAL = ("optimal", "solved", "nothing to do")


@lru_cache(maxsize=1)
def _code_version() -> str:
    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for folder in ("task", "attachment"):
        for path in sorted((root / folder).glob("*.py")):
            h.update(f"{folder}/{path.name}".encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def search_key(scenario: Scenario, context: str) -> str:
    """The key of a search: see the module docstring."""
    sp = scenario.planner
    robots = [(r.name, r.pose, r.covariance, r.radius, r.speed, r.turn_rate) for r in scenario.robots]
    parts = (VERSION, _code_version(), context, robots, scenario.goals, sp.name, sp.encoding, repr(sp.pair_min_gain))
    return hashlib.sha256(repr((*parts, sp.search, sp.costs)).encode()).hexdigest()


def remember(store: EntryStore, key: str, task: TaskResult, budget: float) -> None:
    """Store ``task``, found within ``budget`` seconds (the run's whole time budget)."""
    s = task.search
    if s is None:
        return
    entry: JSON = {
        "budget": budget,
        "status": task.status.value,
        "engine": task.engine,
        "steps": [[list(m) for m in step] for step in task.steps],
        "names": list(task.action_names),
        "search": {
            "mode": s.mode,
            "costs": s.costs,
            "stopped": s.stopped,
            "start": s.start,
            "subproblems": s.subproblems,
            "improvements": s.improvements,
            "seconds": s.seconds,
            "history": [list(h) for h in s.history],
        },
        "bound": None
        if task.bound is None
        else {"value": task.bound.value, "relaxation": task.bound.relaxation, "proved": task.bound.proved_optimal},
    }
    store.put_many({key: entry})


def recall(store: EntryStore, key: str, model: CostModel, goals: Goals, budget: float) -> TaskResult | None:
    """The remembered result, its costs from ``model``; None on a miss, on an entry that is
    damaged or is not a plan of these goals, or on a plan cut short by a smaller budget."""
    entry = store.get_many([key]).get(key)
    if not isinstance(entry, dict):
        return None
    try:
        if entry["search"]["stopped"] not in FINAL and not budget <= float(entry["budget"]):
            return None
        steps: tuple[tuple[MoveKey, ...], ...] = tuple(
            tuple((str(m[0]), str(m[1]), str(m[2])) for m in step) for step in entry["steps"]
        )
        s, b = entry["search"], entry["bound"]
        search = SearchSummary(
            str(s["mode"]),
            str(s["costs"]),
            str(s["stopped"]),
            str(s["start"]),
            int(s["subproblems"]),
            int(s["improvements"]),
            float(s["seconds"]),
            tuple((float(t), float(c)) for t, c in s["history"]),
        )
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
        gap = max(0.0, (cost.total - value) / cost.total) if cost.total > 0 else 0.0
        bound = BoundSummary(value, relaxation, gap, proved)
    counts = TaskCounts(0, 0, 0, sum(len(x) == 2 for x in steps), 0)
    return TaskResult(status, engine, steps, names, cost.steps, counts, True, None, search, bound)
