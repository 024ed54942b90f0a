"""The anytime search's budget: work that gives the same plan on any machine, time as a cap.

A search's budget in seconds gave plans that depended on the machine: on a busy one the
corridor's search stopped before it had solved a sub-problem. So the search counts its work in
ENHSP sub-problems (:attr:`SearchBudget.work`); OR-Tools' first routes stop after a count of
solutions, ENHSP's searches at their plan. What ends on a count ends at the same point on
every machine.

Time stays as a cap: the search's time cap (``--anytime-budget``, or what the run's
``--time-limit`` leaves), OR-Tools' time limit and each sub-problem's ENHSP timeout. Where a cap
bites, the plan is the machine's, and :attr:`SearchBudget.capped` says which cap, for the summary,
plan.json and the regression runs (which then refuse to compare the plan).

Usage: ``budget = SearchBudget(work=80, seconds=math.inf)``; ``budget.left()`` (seconds of the
cap), ``budget.out_of_work(solved)``, ``budget.cap("OR-Tools' time limit")``.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field

#: what ``capped`` names: the caps that can bite
SEARCH_CAP = "the search's time cap"
ROUTING_CAP = "OR-Tools' time limit (first routes)"
SUBPROBLEM_CAP = "a sub-problem's ENHSP time limit"
BOUND_CAP = "the lower bound's share of --time-limit"


@dataclass
class SearchBudget:
    """One search's budget: ``work`` sub-problems (None: no limit), ``seconds`` of time cap from
    its start (inf: none), and the caps that bit so far (in the order they first did)."""

    work: int | None = None
    seconds: float = math.inf
    started: float = field(default_factory=time.perf_counter)
    capped: list[str] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def elapsed(self) -> float:
        return time.perf_counter() - self.started

    def left(self) -> float:
        """Seconds of the time cap left (inf without a cap; at most 0 once it is spent)."""
        return self.seconds - self.elapsed()

    def out_of_time(self) -> bool:
        """Is the time cap spent? (It then counts as having bitten.)"""
        if self.left() > 0:
            return False
        self.cap(SEARCH_CAP)
        return True

    def out_of_work(self, solved: int) -> bool:
        """Have ``solved`` sub-problems spent the work budget?"""
        return self.work is not None and solved >= self.work

    def cap(self, what: str) -> None:
        """Record that ``what`` (a time cap) cut something short: the plan depends on the machine."""
        with self._lock:  # ENHSP's timeouts are told from the searches' threads
            if what not in self.capped:
                self.capped.append(what)
