"""Runs of one plan resumed where they part from an earlier run, not run again from the start.

Keeping robots apart (:mod:`tmpnav.attachment.conflicts`) runs one plan on the team's clock
again and again, each time with other waits (``delays``) or another path for a move
(``detours``). A wait on step k changes nothing before the clock schedules k, that is before
the event at which k's robots end the move before it; a detour changes nothing before k
starts. Every run before that moment is the run already made, event for event. So a run keeps
the clock at the top of each of its events (:class:`Checkpoint`: the state, the events to
come, each robot's steps dispatched, how long its record is), and the next run of the same plan
starts from the last checkpoint before the first step it changes.

The clock's state is an immutable value (:class:`tmpnav.attachment.clock_state.ClockState`) and the
events are replayed from the same heap, so a resumed run makes exactly the calls a run from the
start makes from there on: the same result, to the bit (tests/attachment/test_resume.py).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

if TYPE_CHECKING:
    from tmpnav.task.plans import Plan
    from tmpnav.types import TrajectoryStep

#: the clock's state and a run's result (tmpnav.attachment.clock's ClockState and ClockRun)
S = TypeVar("S")
R = TypeVar("R")

Detours = Mapping[tuple[int, str], tuple[int, ...]]

#: plans whose runs are kept to resume from (the least recently used dropped first), and runs
#: kept per plan (the latest first): a resolution's search goes depth first, each run the one
#: before it with one more wait. Only recorded runs are kept (a plan kept apart is run recorded);
#: a run keeps the team's joint belief at each event, about 15 MB for 32 robots on 200 rooms
MAX_PLANS = 2
MAX_RUNS_PER_PLAN = 3


@dataclass(frozen=True)
class Checkpoint(Generic[S]):
    """The clock at the top of one event of a run: its state, the events still to come (the
    heap as it was), each robot's steps dispatched, and each robot's record's length."""

    state: S
    events: tuple[tuple[int, int], ...]
    done: tuple[int, ...]
    traced: tuple[int, ...]


@dataclass(frozen=True)
class Made(Generic[S, R]):
    """A run made: its waits (control steps by plan step, none zero) and detours, its
    checkpoints (one per event), the event that scheduled each step (-1: before the first) and
    the event that started it, its record (robot index -> belief steps) and its result."""

    held: Mapping[int, int]
    detours: Detours
    checkpoints: tuple[Checkpoint[S], ...]
    pushed: Mapping[int, int]
    dispatched: Mapping[int, int]
    steps: Mapping[int, list[TrajectoryStep]]
    segments: Mapping[int, list[Any]]  # where the steps came from (tmpnav.attachment.record.Trace)
    run: R


@dataclass(frozen=True)
class Resume(Generic[S, R]):
    """Where a run starts from: ``made``'s checkpoint ``at`` (``at`` None: ``made`` is the run)."""

    made: Made[S, R]
    at: int | None


class Resumes(Generic[S, R]):
    """The runs kept to resume from, by plan."""

    def __init__(self) -> None:
        self._plans: OrderedDict[Plan, list[Made[S, R]]] = OrderedDict()

    def find(self, plan: Plan, held: Mapping[int, int], detours: Detours) -> Resume[S, R] | None:
        """The kept run of ``plan`` that the run with ``held`` and ``detours`` parts from latest,
        and where; None when none is kept, or each parts before its first event."""
        best: Resume[S, R] | None = None
        for made in self._plans.get(plan, ()):
            at = parting(made, held, detours)
            if at is None:
                self._plans.move_to_end(plan)
                return Resume(made, None)
            if at >= 0 and (best is None or at > (best.at or 0)):
                best = Resume(made, at)
        return best

    def keep(self, plan: Plan, made: Made[S, R]) -> None:
        runs = self._plans.setdefault(plan, [])
        runs.insert(0, made)
        del runs[MAX_RUNS_PER_PLAN:]
        self._plans.move_to_end(plan)
        while len(self._plans) > MAX_PLANS:
            self._plans.popitem(last=False)


def parting(made: Made[S, R], held: Mapping[int, int], detours: Detours) -> int | None:
    """The first event at which a run with ``held`` and ``detours`` differs from ``made``
    (-1: before its first event), None when it does not differ at all."""
    changed = [made.pushed.get(k, -1) for k in set(held) | set(made.held) if held.get(k, 0) != made.held.get(k, 0)]
    ways = set(detours) | set(made.detours)
    changed += [made.dispatched.get(k, -1) for k, r in ways if detours.get((k, r)) != made.detours.get((k, r))]
    return min(changed) if changed else None
