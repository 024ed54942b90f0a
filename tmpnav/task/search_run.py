"""What an anytime search (:mod:`tmpnav.task.search`) runs with and gives: its options, its run
(the clock it keeps, who is told of its progress, its bound and its time limit), what it did and
what it found."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol, runtime_checkable

from tmpnav.choices import StopReason
from tmpnav.deadline import Deadline
from tmpnav.results import SearchProgress, StageTimes
from tmpnav.task.model import PlanCost
from tmpnav.task.plans import Plan, Step

#: a plan's cost as it will be executed, from the plan and its cost as planned
#: (tmpnav.attachment.apart.ExecutedCost: robots kept apart)
Executed = Callable[[Plan, PlanCost], PlanCost]


@runtime_checkable
class KeepsApart(Protocol):
    """An ``Executed`` that says which robots it kept apart in a plan it priced, and which pairs
    of them nothing kept apart."""

    def robots_apart(self, plan: Plan) -> frozenset[str]: ...

    def robots_stuck(self, plan: Plan) -> frozenset[tuple[str, str]]: ...


@dataclass(frozen=True)
class SearchRun:
    """What a search runs with beside its problem: the run's stage times (and so its clock) and
    who is told of its progress."""

    times: StageTimes = field(default_factory=StageTimes)
    progress: SearchProgress | None = None
    #: the lower bound told with every event, asked for at the first (it may still be computing)
    bound: Callable[[], float] | None = None
    #: called once the single moves are costed (the run starts computing its bound then)
    costed: Callable[[], None] | None = None
    #: ENHSP's plans of the sub-problems solved so far, by their PDDL text (domain, problem)
    #: (``replace`` keeps the same dict), see :meth:`AnytimeSearch._known`
    solved: dict[tuple[str, str], list[Step] | None] = field(default_factory=dict, compare=False, hash=False)
    #: the run's time limit (tmpnav.deadline): past it the search returns its best plan
    deadline: Deadline = field(default_factory=Deadline, compare=False, hash=False)

    def bounded(self, bound: Callable[[], float] | None, costed: Callable[[], None] | None = None) -> SearchRun:
        """The same run, telling the value ``bound`` gives with its events, and calling
        ``costed`` once the single moves are costed."""
        return replace(self, bound=bound, costed=costed)

    def note(self, best: float, what: str) -> None:
        """Tell of an event: the run's time (the run's one clock), the best cost, the bound."""
        if self.progress is not None:
            bound = None if self.bound is None else self.bound()
            self.progress(self.times.elapsed(), best, bound, what)


@dataclass(frozen=True)
class SearchOptions:
    """How the anytime search runs."""

    planner: str = "enhsp-blind"  # the ENHSP engine of the sub-problems (optimal)
    encoding: str = "mixed"  # single | mixed
    min_gain: float = 0.05  # mixed: pairs must save this fraction
    budget: float = 60.0  # seconds for the whole search: its time cap (inf: none)
    work: int | None = None  # sub-problems ENHSP may solve (None: no limit), the budget of work
    #: rooms per neighbourhood, grown when a round brings nothing (on building-like tables of
    #: 10-12 rooms, (6, 8) reached the optimum as often as (4, 6, 8) with half the sub-problems)
    sizes: tuple[int, ...] = (6, 8)
    sub_robots: int = 3  # robots per neighbourhood, at most
    sub_timeout: float = 30.0  # seconds for one sub-problem's ENHSP run
    routing_time: float | None = None  # OR-Tools' time limit; None: a quarter of the budget, 1-30 s
    seed: int = 0
    parallel: int = min(2, os.cpu_count() or 1)  # sub-problems ENHSP solves at once
    #: the model's costs are context-free (a cost table): a sub-problem that is the whole
    #: problem, solved optimally by ENHSP, proves the plan optimal
    whole_is_exact: bool = True
    #: the objective's price of a second of makespan (tmpnav.task.objectives): plans are
    #: compared by their cost plus this times their makespan, the team moving at once
    span_weight: float = 0.0
    #: edits between routes costed by the model per pass, the best by the single moves first
    route_candidates: int = 6
    #: OR-Tools' routes as a first plan; False: the seeds', where there are seeds (a search that
    #: goes on from an exact plan, which OR-Tools' routes of single moves cannot beat as planned)
    first_routes: bool = True
    #: the work rooms each robot should enter, planner.min_rooms (tmpnav.task.minimum; 0: none)
    min_rooms: int = 0


@dataclass
class SearchStats:
    """What the search did (plan.json ``task.search``)."""

    subproblems: int = 0  # sub-problems ENHSP solved
    reused: int = 0  # sub-problems met again, whose plan ENHSP had already given (not solved again)
    improvements: int = 0
    route_improvements: int = 0  # of those, by edits between routes (tmpnav.task.routes)
    rounds: int = 0
    history: list[tuple[float, float]] = field(default_factory=list)  # (seconds, best cost)


@dataclass(frozen=True)
class SearchResult:
    plan: Plan
    cost: PlanCost
    stopped: StopReason  # "optimal" | "converged" | "work budget" | "time budget" | "nothing to do"
    stats: SearchStats
    start: str  # how the first plan was found
    capped: tuple[str, ...] = ()  # the time caps that cut something short (tmpnav.task.budget)
