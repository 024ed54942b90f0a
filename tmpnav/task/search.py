"""The anytime task planner: large-neighbourhood search whose repairs ENHSP plans exactly.

At building scale (20-60 rooms, up to 8 robots) the exact problem is too big for one
optimal ENHSP search, but any part of it a few rooms and robots wide is small. The search:

1. **Start.** OR-Tools routes the robots through the goal rooms on the single-move costs
   (:mod:`tmpnav.task.first_routes`, :mod:`tmpnav.task.routing`): a plan of single moves, usually good, within seconds.
   Where the objective prices time, a second routing puts the longest route first, and the
   better of the two by the objective is the start (:meth:`AnytimeSearch._makespan_first`).
2. **Improve.** Repeatedly open the plan around a seed room: up to ``sub_robots`` robots
   whose routes pass near it and a contiguous stretch of each route, ``size`` rooms in all.
   The sub-problem -- those robots, from where they are at that point of the plan, must
   visit those rooms, each ending where its stretch ended when the robot has moves after
   it -- is costed by the cost model from the robots' states at that point (paired moves
   included) and solved optimally by ENHSP through unified-planning
   (:mod:`tmpnav.task.subproblems`, :mod:`tmpnav.task.pddl_text`). Its plan replaces the
   stretch; the whole plan is costed again by the model, and kept if it is cheaper. ENHSP
   decides every step of the plan.
3. **Between robots.** When a round of neighbourhoods of every size has covered every room
   without an improvement, the routes are edited as vehicle routing's local searches edit
   them (:mod:`tmpnav.task.routes`): a room moved to another robot's route (relocate), two
   robots' rooms swapped (exchange), two or three robots' route tails swapped or passed round
   (2-opt*). Every edit is screened on the single moves' costs and durations, the price of
   keeping the best plan's robots apart counted for the edits that leave their routes as they
   are, and the few best are costed by the model; a better plan starts the neighbourhoods
   again. A neighbourhood opens a stretch of each route whose ends stay where they were, so
   moving work from a robot that finishes last to one that finishes early is what it cannot
   do (the makespan stayed 11-13% above the optimum on 2 of 25 generated offices,
   benchmarks/references/). Where the makespan counts,
   the edits include unloadings (:mod:`tmpnav.task.balance`): relocations chained from the
   robot that finishes last. A fleet (more robots than a neighbourhood holds) starts with the
   routes' edits, until they bring nothing, and where time is priced its first routes insert
   every room where it adds least into all routes at once (:data:`FLEET_FIRST_SOLUTION`).
   With a minimum of rooms per robot (planner.min_rooms, :mod:`tmpnav.task.minimum`) every plan
   is ranked with the rooms its robots lack priced, and the first routes and the edits keep to it.
4. **Stop** when the lower bound proves the plan optimal, when neither the neighbourhoods nor
   the routes' edits improve the plan (a local optimum of both), or when its budget is spent:
   a count of sub-problems, so the same plan on any machine, with time as a cap
   (:mod:`tmpnav.task.budget`, which also says when a cap bit).

The plan returned is always one the model has costed in full, so its cost is the model's
cost of that plan; the lower bound (:mod:`tmpnav.task.bound`, computed by the caller over
the plan space) says how far from optimal it can be.
"""

from __future__ import annotations

import contextlib
import functools
import random
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Literal

from tmpnav.beside import Beside
from tmpnav.choices import StopReason
from tmpnav.errors import PlannerError, PlannerTimeoutError, TimeLimitError, UnsolvableError
from tmpnav.lifetime import gather
from tmpnav.task import budget as caps
from tmpnav.task.budget import SearchBudget
from tmpnav.task.decode import canonical_order
from tmpnav.task.first_routes import first_routes, no_routes
from tmpnav.task.model import CostModel, PlanCost
from tmpnav.task.neighbourhoods import Closeness, Neighbourhood, neighbourhood
from tmpnav.task.objectives import MAKESPAN_WEIGHT
from tmpnav.task.plans import Plan, Rules, Step, splice, with_missing, with_origins
from tmpnav.task.pricing import Pricing
from tmpnav.task.routes import KeptApartPrice, route_edits
from tmpnav.task.routing import Routes
from tmpnav.task.search_run import Executed, KeepsApart, SearchOptions, SearchResult, SearchRun, SearchStats
from tmpnav.task.solve import Background
from tmpnav.task.subproblems import Encoding, Sub, SubProblems
from tmpnav.types import CostTable, Goals

#: relative improvement below which a new plan does not count as better
EPSILON = 1e-9


@dataclass(frozen=True)
class _Batch:
    """Sub-problems tried together, each with ENHSP's plan or the search that gives it.

    A sub-problem is its PDDL text: the same text is the same problem to ENHSP, whose optimal
    search is deterministic, so its plan is the one it gave before (``SearchRun.solved``), or
    will give (a search under way), and running it again cannot pay. The text holds every
    cost, the goals, the ends and the clocks, so a neighbourhood met again on an unchanged
    part of the plan (same robots, rooms, beliefs at its start and, with time priced, the same
    clocks) is such a sub-problem. A search that found no plan in time is not remembered (a
    longer timeout might find one)."""

    subs: list[Sub]
    plans: list[Future[list[Step] | None] | list[Step] | None]  # None: no plan, or no time to search
    state: tuple[object, ...]  # the random generator's state after the batch was drawn (() if not drawn)


class AnytimeSearch:
    """One run of the anytime search on a cost model."""

    def __init__(
        self,
        model: CostModel,
        goals: Goals,
        options: SearchOptions,
        run: SearchRun | None = None,
        proves_optimal: Callable[[float], bool] | None = None,
        executed: Executed | None = None,
    ):
        self.model, self.goals, self.options = model, goals, options
        self.executed = executed
        self.watch = run if run is not None else SearchRun()
        self.times = self.watch.times
        self.rules = Rules(model.start_location, goals)
        self.proves_optimal = proves_optimal or (lambda cost: False)
        self.rng = random.Random(options.seed)
        self.stats = SearchStats()
        self.t0 = time.perf_counter()
        self.budget = SearchBudget(options.work, options.budget, self.t0)
        self._timed_out: set[tuple[str, str]] = set()  # sub-problems whose ENHSP search hit its time limit
        self.near = Closeness(CostTable((), (), (), {}, {}, {}), model.start_location, model.robots)
        encoding = Encoding(options.encoding, options.min_gain, options.span_weight)
        self.subs = SubProblems(model, goals, self.rules, encoding, self.times)
        self.singles = CostTable((), (), (), {}, {}, {})
        self._stack = contextlib.ExitStack()
        self._solver: Background | None = None
        self._running: dict[tuple[str, str], Future[list[Step] | None]] = {}  # searches by their text
        self.pricing = Pricing(model, goals, options, self.times, executed)

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def left(self) -> float:
        """Seconds of the search's time cap left."""
        return self.budget.left()

    def _spent(self) -> Literal["work budget", "time budget"] | None:
        """Why the search may start no more sub-problems, if it may not: its work budget is spent
        (the sub-problems solved so far, the same count on every machine), or its time cap."""
        if self.budget.out_of_work(self.stats.subproblems):
            return "work budget"
        return "time budget" if self.budget.out_of_time() else None

    # ------------------------------------------------------------------ start

    def first_plan(
        self,
        singles: CostTable,
        start_from: Plan | None = None,
        span_weight: float | None = None,
        routed: Callable[[], tuple[Routes, bool]] | None = None,
    ) -> tuple[Plan, str]:
        """OR-Tools' routes on the single moves, as a plan of single moves; its local search
        starts from ``start_from``'s routes when given (a replan's plan under way). The routes
        minimise the sum of the moves' costs plus ``span_weight`` (default: the objective's) per
        second of the longest route. ``routed``: those routes, computed beside (:meth:`_routing`)."""
        with self.times.timed("planner"):
            routes, timed_out = (routed or self._routing(singles, start_from, span_weight))()
            if timed_out:
                self.budget.cap(caps.ROUTING_CAP)
        if not routes.found:
            raise PlannerError(no_routes(routes))
        plan = with_origins([((m[0], m[2]),) for m in routes.moves(singles)], self.model.start_location)
        return self.canonical(plan), routes.method

    def _routing(
        self, singles: CostTable, start_from: Plan | None, span_weight: float | None
    ) -> Callable[[], tuple[Routes, bool]]:
        """OR-Tools' first routes of :meth:`first_plan`, to compute in line or beside; their time
        limit counts from now."""
        opts = self.options
        return functools.partial(
            first_routes,
            singles,
            self.goals,
            self.model.robots,
            budget=opts.budget,
            routing_time=opts.routing_time,
            time_left=self.left(),
            fleet=self.fleet,
            span_weight=opts.span_weight if span_weight is None else span_weight,
            start_from=start_from,
            second=span_weight is not None,
            min_rooms=self.pricing.need,
        )

    def _makespan_routing(self, singles: CostTable, seeds: dict[str, Plan]) -> Beside[tuple[Routes, bool]] | None:
        """The routes of a second first plan where the objective prices time below the makespan
        objective's price, for a team planned from scratch (no plan under way): OR-Tools' routes
        with the longest route first (:data:`MAKESPAN_WEIGHT` per second). Routes that price time
        lightly can leave a robot idle that a search from them does not put to work:
        building-4robots with the AMCL model, on RPP's motions with sharp corners, converged at
        583.5 with r3 on 2 rooms from the weighted routes, and at 562.3 with every robot on 4-6
        rooms from these (tmpnav.task.objectives). Computed beside the first routing (OR-Tools
        searches without the interpreter's lock), each routing's own solutions as in line; None
        where there is none."""
        weight = self.options.span_weight
        if not weight or weight >= MAKESPAN_WEIGHT or len(self.model.robots) < 2 or UNDER_WAY in seeds:
            return None
        return Beside(self._routing(singles, None, MAKESPAN_WEIGHT), "tmpnav-makespan-routing")

    def _makespan_first(self, singles: CostTable, routed: Beside[tuple[Routes, bool]] | None) -> list[tuple[str, Plan]]:
        """The second first plan from its ``routed`` routes (:meth:`_makespan_routing`); none
        where the first routing ran out of its time limit (at 200 rooms it takes all of its 30 s:
        the first plan is then the machine's already)."""
        if routed is None or caps.ROUTING_CAP in self.budget.capped:
            return []
        try:
            plan, method = self.first_plan(singles, span_weight=MAKESPAN_WEIGHT, routed=routed)
        except PlannerError:
            return []
        return [(f"{method}, the makespan first", plan)]

    @property
    def fleet(self) -> bool:
        """More robots than a neighbourhood holds: work moves between some of them only by the
        routes' edits."""
        return len(self.model.robots) > self.options.sub_robots

    def canonical(self, plan: Plan) -> Plan:
        """The plan's steps in the canonical order of commuting steps (tmpnav.task.decode)."""
        return tuple(plan[i] for i in canonical_order(list(plan), self.model.robots))

    def run(self, seeds: dict[str, Plan] | None = None) -> SearchResult:
        """Search from the cheapest of OR-Tools' routes and the ``seeds`` (name -> plan,
        e.g. the exact plan of the cost table) until the plan is proved optimal, a local
        optimum, or the budget is spent."""
        with self._stack:  # ENHSP's searches in the background end with the run
            return self._run(seeds)

    @property
    def solver(self) -> Background:
        """ENHSP's searches in the background (started with the first one)."""
        if self._solver is None:
            self._solver = self._stack.enter_context(Background(self.options.parallel))
        return self._solver

    def _run(self, seeds: dict[str, Plan] | None) -> SearchResult:
        with self.times.timed("oracle"):
            singles = self.model.singles(self.goals)
        if self.watch.costed is not None:
            self.watch.costed()
        self.singles = singles
        self.near = Closeness(singles, self.model.start_location, self.model.robots)
        taken = set(self.goals.all_rooms) | set(self.model.start_location.values())
        self.subs.waypoints = tuple(dict.fromkeys(t for _, _, t in singles.single if t not in taken))
        # the seeds with a replan's new goals put in; OR-Tools' routes start from the plan under way
        valid = {
            name: p
            for name, seed in (seeds or {}).items()
            if self.rules.valid(p := self.canonical(with_missing(seed, self.rules, singles)))
        }
        starts = list(valid.items())
        if self.options.first_routes or not starts:
            second = self._makespan_routing(singles, valid)  # beside the first
            try:
                plan, routed = self.first_plan(singles, valid.get(UNDER_WAY))
            except PlannerError:
                if not starts:
                    raise
            else:  # no routes found in time: the seeds (a replan's repaired plan) are the first plans
                starts.insert(0, (routed, plan))
            starts.extend(self._makespan_first(singles, second))
        (start, best), cost = starts[0], self.pricing.priced(starts[0][1], self.pricing.cost(starts[0][1]))
        for name, seed in starts[1:]:
            seed_cost = self.pricing.priced(seed, self.pricing.cost(seed))
            if self.pricing.value(seed_cost) < self.pricing.value(cost):
                best, cost, start = seed, seed_cost, name
        self.rules.check(best)
        self._note(cost, "first plan")
        if not best:
            return SearchResult(best, cost, "nothing to do", self.stats, start, tuple(self.budget.capped))
        self.best, self.best_cost = best, cost
        # a plan: from here the search's time cap (the run's limit among its caps) ends it, between
        # batches, and the oracle no longer cuts its work short
        self.watch.deadline.disarm()
        try:
            return self._improve(start)
        except TimeLimitError:  # the run's time limit passed in the oracle's work: the best plan so far
            self.budget.cap(caps.SEARCH_CAP)
            return self._result("time budget", start)

    def _improve(self, start: str) -> SearchResult:
        """The search from its first plan (``self.best``) on."""
        best = self.best
        if self.options.whole_is_exact and self._fits_one_neighbourhood(best):
            # the whole problem is one sub-problem: ENHSP's optimal plan of it is the optimum
            whole = Neighbourhood(
                tuple(self.model.robots),
                frozenset(range(len(best))),
                tuple(dict.fromkeys(m[2] for step in best for m in step)),
                {},
            )
            if self._try_batch(best, [whole], keep_equal=True, every_pair=True):
                return self._result("optimal", start)
        return self._result(self._improve_until_done(self.best, self.best_cost), start)

    def _result(self, stopped: StopReason, start: str) -> SearchResult:
        return SearchResult(self.best, self.best_cost, stopped, self.stats, start, tuple(self.budget.capped))

    def _fits_one_neighbourhood(self, plan: Plan) -> bool:
        rooms = {m[2] for step in plan for m in step}
        return len(rooms) <= self.options.sizes[-1] and len(self.model.robots) <= self.options.sub_robots

    # ------------------------------------------------------------------ improve

    def _improve_until_done(self, best: Plan, cost: PlanCost) -> StopReason:
        self.best, self.best_cost = best, cost
        size_index = 0
        if self.fleet:
            # a fleet: no neighbourhood holds every robot, and work moves between robots only by
            # the routes' edits, which ENHSP does not solve: those first, while they improve
            while not self.budget.out_of_time() and self._between_routes(first=True):
                pass
        while True:
            if self.proves_optimal(self.pricing.value(self.best_cost)):
                return "optimal"
            outcome = self._round(self.options.sizes[size_index])
            self.stats.rounds += 1
            if outcome in ("work budget", "time budget", "optimal"):
                return outcome
            if outcome == "improved":
                size_index = 0
            elif size_index + 1 < len(self.options.sizes):
                size_index += 1
            elif self._between_routes():
                size_index = 0
            elif self.budget.out_of_time():
                return "time budget"
            else:
                return "converged"

    def _between_routes(self, first: bool = False) -> bool:
        """The best plan's routes edited (:func:`tmpnav.task.routes.route_edits`): the edits the
        single moves say are best, up to ``route_candidates`` of them, costed by the model; the
        cheapest kept if it beats the best plan. True when one did. With ``first``, the first
        that beats it, best by the single moves first: a fleet's plan costs a second or more to
        cost, and most passes keep the edit the screen put first."""
        with self.times.timed("planner"):
            edits = route_edits(
                self.best,
                self.singles,
                self.goals,
                self.rules,
                self.options.span_weight,
                apart=self._apart_price(),
                least=(self.pricing.need, self.pricing.work),
            )
        costed: list[tuple[Plan, PlanCost, None]] = []
        best: tuple[Plan, PlanCost, None] | None = None
        for edit in edits[: self.options.route_candidates]:
            if self.budget.out_of_time():
                break
            candidate = self.canonical(with_origins(edit, self.model.start_location))
            if not self.rules.valid(candidate) or self.pricing.hopeless(candidate, self.best_cost):
                continue
            costed.append((candidate, self.pricing.cost(candidate), None))
            best = self.pricing.cheapest(costed[-1:], self.best_cost) if first else None
            if (
                best is not None
                and self.pricing.value(best[1]) < self.pricing.value(self.best_cost) * (1 - EPSILON) - EPSILON
            ):
                break
        best = best if first else self.pricing.cheapest(costed, self.best_cost)
        if best is None:
            return False
        new, old = self.pricing.value(best[1]), self.pricing.value(self.best_cost)
        if not new < old * (1 - EPSILON) - EPSILON:
            return False
        self.best, self.best_cost = best[0], best[1]
        self.stats.improvements += 1
        self.stats.route_improvements += 1
        self._note(self.best_cost, "between routes")
        return True

    def _apart_price(self) -> KeptApartPrice:
        """What keeping the best plan's robots apart adds to its objective, and the robots kept
        apart (:class:`tmpnav.task.routes.KeptApartPrice`)."""
        if not isinstance(self.executed, KeepsApart):
            return KeptApartPrice()
        slack = self.pricing.value(self.best_cost) - self.pricing.value(self.pricing.cost(self.best))
        robots = self.executed.robots_apart(self.best)
        stuck = self.executed.robots_stuck(self.best)
        return KeptApartPrice(slack, robots, stuck) if slack > 0 and robots else KeptApartPrice()

    def _round(self, size: int) -> Literal["improved", "unchanged", "work budget", "time budget", "optimal"]:
        """Neighbourhoods of ``size`` rooms around seeds until every room was in one
        ('improved' or 'unchanged'); the round starts again on each improved plan. Ends
        early with 'work budget', 'time budget' or 'optimal'."""
        improved = False
        while True:
            outcome = self._sweep(self.best, size)
            if outcome != "improved":
                return "improved" if improved and outcome == "unchanged" else outcome
            improved = True
            if self.proves_optimal(self.pricing.value(self.best_cost)):
                return "optimal"

    def _sweep(self, plan: Plan, size: int) -> Literal["improved", "unchanged", "work budget", "time budget"]:
        """Try the batches of neighbourhoods of one sweep of ``plan`` (:meth:`_batches`) until
        one improves it ('improved'), every one was tried ('unchanged') or the budget is spent.

        A batch's sub-problems are costed in the oracle while ENHSP plans the batch before
        (:class:`tmpnav.task.solve.Background`): on two cores the two overlap. The plan is
        the one the batches would give one after the other: a batch drawn ahead of an
        improvement is dropped, and the random generator is put back as it was when the
        improving batch had been drawn (its next sweep draws the same neighbourhoods). The work
        budget is looked at before a batch starts, on the sub-problems of the batches settled
        before the one under way: the same count on every machine."""
        before: _Batch | None = None
        for hoods, state in self._batches(plan, size):
            if (spent := self._spent()) is not None:
                if before is not None and self._settle(plan, before):
                    self.rng.setstate(before.state)
                    return "improved"
                return spent
            batch = self._launch(plan, hoods, state)
            if before is not None and self._settle(plan, before):
                self._drop(batch)
                self.rng.setstate(before.state)
                return "improved"
            before = batch
        return "improved" if before is not None and self._settle(plan, before) else "unchanged"

    def _batches(self, plan: Plan, size: int) -> Iterator[tuple[list[Neighbourhood], tuple[object, ...]]]:
        """The batches of one sweep: neighbourhoods of ``size`` rooms around seeds in random
        order, each seed's room not yet in one, ``parallel`` new ones a batch (the last may
        be smaller, even empty); each with the random generator's state after it was drawn."""
        seeds = [(k, i) for k, step in enumerate(plan) for i in range(len(step))]
        self.rng.shuffle(seeds)
        covered: set[str] = set()
        tried: set[tuple[tuple[str, ...], frozenset[int]]] = set()
        batch: list[Neighbourhood] = []
        for n, (k, i) in enumerate(seeds):
            if plan[k][i][2] not in covered:
                hood = neighbourhood(plan, k, i, size, self.near, self.rng, self._robots_for(size))
                covered.update(hood.rooms)
                if (hood.robots, hood.removed) not in tried:
                    tried.add((hood.robots, hood.removed))
                    batch.append(hood)
            if len(batch) < self.options.parallel and n + 1 < len(seeds):
                continue
            yield batch, self.rng.getstate()
            batch = []

    def _try_batch(
        self, plan: Plan, hoods: list[Neighbourhood], keep_equal: bool = False, every_pair: bool = False
    ) -> bool:
        """Solve the sub-problems of ``hoods`` and keep the cheapest spliced plan if it beats
        the best one (or ties it, with ``keep_equal``: then True means ENHSP solved them);
        ``every_pair``: each offers every paired move that saves ``min_gain`` (the whole problem,
        whose plan is then the optimum), not only the few that save most."""
        return self._settle(plan, self._launch(plan, hoods, (), every_pair), keep_equal)

    def _launch(
        self, plan: Plan, hoods: list[Neighbourhood], state: tuple[object, ...], every_pair: bool = False
    ) -> _Batch:
        """The sub-problems of ``hoods`` costed, and ENHSP started on those not solved before."""
        subs = [sub for hood in hoods if (sub := self.subs.of(plan, hood, self.best_cost, every_pair)) is not None]
        timeout = min(self.options.sub_timeout, self.left())
        plans: list[Future[list[Step] | None] | list[Step] | None] = []
        for sub in subs:
            texts = sub.task.texts()
            known = self.watch.solved.get(texts)
            if known is not None:
                plans.append(known)
            elif texts in self._running:
                plans.append(self._running[texts])
            elif timeout > 0.05:
                future = self.solver.submit(functools.partial(self._solve, sub, timeout))
                self._running[texts] = future
                plans.append(future)
            else:  # no time left to solve it
                self.budget.cap(caps.SEARCH_CAP)
                plans.append(None)
        return _Batch(subs, plans, state)

    def _drop(self, batch: _Batch) -> None:
        """A batch drawn ahead of an improvement: ENHSP need not start its searches."""
        for sub, found in zip(batch.subs, batch.plans, strict=True):
            if isinstance(found, Future) and found.cancel():
                self._running.pop(sub.task.texts(), None)

    def _settle(self, plan: Plan, batch: _Batch, keep_equal: bool = False) -> bool:
        """ENHSP's plans of a batch waited for, spliced into ``plan``, and the cheapest kept if it
        beats the best one (or ties it, with ``keep_equal``: then True means ENHSP solved them)."""
        if not batch.subs:
            return False
        steps: list[list[Step] | None] = []
        with self.times.timed("planner"):
            for sub, found in zip(batch.subs, batch.plans, strict=True):
                if not isinstance(found, Future):
                    self.stats.reused += found is not None
                    steps.append(found)
                    continue
                solved = next(gather([found]))
                if self._running.pop(sub.task.texts(), None) is found:
                    self.stats.subproblems += 1
                    if solved is not None:
                        self.watch.solved[sub.task.texts()] = solved
                if solved is None and sub.task.texts() in self._timed_out:
                    self.budget.cap(caps.SUBPROBLEM_CAP)
                else:  # a search two batches asked for: counted once
                    self.stats.reused += 1
                steps.append(solved)
        costed: list[tuple[Plan, PlanCost, Sub]] = []
        for sub, found in zip(batch.subs, steps, strict=True):  # in the neighbourhoods' order
            if found is None:
                continue
            candidate = self.canonical(splice(sub.opened, found, self.model.start_location))
            if not self.rules.valid(candidate) or self.pricing.hopeless(candidate, self.best_cost):
                continue
            costed.append((candidate, self.pricing.cost(candidate), sub))
        best = self.pricing.cheapest(costed, self.best_cost)
        if best is None:
            return False
        new, old = self.pricing.value(best[1]), self.pricing.value(self.best_cost)
        if not new < old * (1 - EPSILON) - EPSILON:
            return keep_equal and new <= old * (1 + EPSILON) + EPSILON
        candidate, cost, sub = best
        self.best, self.best_cost = candidate, cost
        self.stats.improvements += 1
        self._note(cost, f"{len(sub.hood.robots)} robots, {len(sub.hood.rooms)} rooms")
        return True

    def _solve(self, sub: Sub, timeout: float) -> list[Step] | None:
        """ENHSP's optimal plan of a sub-problem (None if it found none in time, or none at
        all). A planner that fails otherwise (it crashed, or cannot run) fails the search: it
        used to count as a sub-problem solved without improvement, so a run whose every ENHSP
        search crashed (a bad TMPNAV_JAVA_OPTIONS) "converged" on OR-Tools' first plan."""
        try:
            return sub.task.decode(sub.task.solve(self.options.planner, timeout))
        except PlannerTimeoutError:
            self._timed_out.add(sub.task.texts())  # its plan depends on the machine's speed
            return None
        except UnsolvableError:
            return None

    # ------------------------------------------------------------------ progress

    def _robots_for(self, size: int) -> int:
        """Robots of a neighbourhood: all allowed in the largest ones, 2 or more otherwise."""
        most = max(1, self.options.sub_robots)
        if size == self.options.sizes[-1]:
            return most
        return self.rng.randint(min(2, len(self.model.robots)), most)

    def _note(self, cost: PlanCost, what: str) -> None:
        """The search's progress: the objective of its best plan (without the rank's price of
        conflicts left, which are told in words)."""
        value = cost.value(self.options.span_weight)
        if cost.unsafe:
            what = f"{what}; robots in each other's way: {cost.unsafe}"
        if cost.short:
            what = f"{what}; rooms short of planner.min_rooms: {cost.short}"
        self.stats.history.append((round(self.elapsed(), 3), value))
        self.watch.note(value, what)


#: the name of a seed that is the plan being executed (a replan's incumbent): OR-Tools' routes
#: start from it
UNDER_WAY = "the plan being executed"


def search(
    model: CostModel,
    goals: Goals,
    options: SearchOptions,
    run: SearchRun | None = None,
    proves_optimal: Callable[[float], bool] | None = None,
    seeds: dict[str, Plan] | None = None,
    executed: Executed | None = None,
) -> SearchResult:
    """Run the anytime search (see the module docstring); ``executed`` prices a plan as it will
    be executed (robots kept apart), from its cost as planned."""
    return AnytimeSearch(model, goals, options, run, proves_optimal, executed).run(seeds)
