"""The run's time limit (``--time-limit``, ``planner.time_limit``): one clock for the whole run.

A :class:`Deadline` is made when a run starts and handed down with its clock (the search's
:class:`tmpnav.task.search.SearchRun`). The stages look at it where they can stop cleanly:

* the oracle between its blocks of work (its progress, :meth:`Deadline.watch`), so a stage
  that computes costs for minutes ends within a block of the limit;
* the pipeline between stages (:meth:`Deadline.check`);
* the anytime search, whose time cap it lowers: past it the search returns its best plan.

A command's limit counts from the command's start (:data:`COMMAND_STARTED`, which ``tmpnav``
sets before it loads anything else; the Python API's runs count from their own start), and
the search leaves :meth:`Deadline.after_search` of it to the stages after it (keeping robots
apart, the re-simulation, the plan's files and figures), so that the command ends by the limit.

Once the run has a plan (the anytime search's first, or the task stage's) the deadline is
disarmed (:meth:`Deadline.disarm`): the search's time cap, which the limit lowered, ends the
search between its batches, and the plan's re-simulation, which its report needs, runs to
its end. Before any plan, passing the
limit raises :class:`tmpnav.errors.TimeLimitError` (exit code 5), which the pipeline completes
with the stage that took the time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from tmpnav.errors import TimeLimitError

#: when the ``tmpnav`` command started (``time.perf_counter``), set by ``tmpnav.__main__`` before
#: it loads the command line; None in a program that uses tmpnav's API
COMMAND_STARTED: float | None = None
#: the share of a time limit the search leaves to the stages after it, at least AFTER_SEARCH_MIN
#: seconds and AFTER_SEARCH_PER_GOAL seconds a goal: the re-simulation, the plan's files and
#: figures grow with the plan (2-3 s on 40 rooms and 8 robots, 5 s on 100 rooms and 16, about
#: 15 s on 200 rooms and 2 robots, whose plan is 5,500 s long)
AFTER_SEARCH_SHARE = 0.08
AFTER_SEARCH_MIN = 2.5
AFTER_SEARCH_PER_GOAL = 0.075


def run_started(own: float) -> float:
    """When a run's time limit starts: the command's start for the command's first run, else
    ``own`` (the run's own start, ``time.perf_counter``): the replans of a closed loop and the
    plans of ``tmpnav serve`` each count from their own start."""
    global COMMAND_STARTED
    started, COMMAND_STARTED = COMMAND_STARTED, None
    return started if started is not None and own >= started else own


@dataclass
class Deadline:
    """``seconds`` from ``started`` (``time.perf_counter``; None: no limit)."""

    seconds: float | None = None
    started: float = field(default_factory=time.perf_counter)
    armed: bool = True  # False once the run has a plan: the stages after it finish

    def left(self) -> float:
        """Seconds until the limit (inf without one)."""
        if self.seconds is None:
            return math.inf
        return self.seconds - (time.perf_counter() - self.started)

    def after_search(self, goals: int = 0) -> float:
        """Seconds of the limit kept for the stages after the search of a plan of ``goals`` goals
        (0 without a limit)."""
        if self.seconds is None:
            return 0.0
        return max(AFTER_SEARCH_MIN, AFTER_SEARCH_SHARE * self.seconds, AFTER_SEARCH_PER_GOAL * goals)

    def passed(self) -> bool:
        return self.armed and self.left() <= 0

    def check(self) -> None:
        """Raise TimeLimitError when the limit has passed and the run has no plan yet."""
        if self.passed():
            raise TimeLimitError(f"no plan within --time-limit {self.seconds:g} s", self.seconds or 0.0)

    def disarm(self) -> None:
        """The run has its plan: what follows finishes past the limit."""
        self.armed = False

    def watch(self, progress: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
        """``progress`` (of the oracle: requests done, in all) that also looks at the limit."""

        def told(done: int, total: int) -> None:
            if progress is not None:
                progress(done, total)
            self.check()

        return told
