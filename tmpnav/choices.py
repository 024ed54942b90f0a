"""The task stage's choices, in one place: encodings, costs, searches, objectives, and the rule
that picks a search.

A leaf module (it imports nothing of tmpnav): the scenario format, its checks, the command
line, the planning stage and the reports all take their choices and their names from here,
so a choice is added once. What each choice *does* lives in its registry: the encodings in
:data:`tmpnav.task.encodings.ENCODINGS`, the task planners in
:data:`tmpnav.planning.PLANNERS` (one per search and costs).

``COSTS``, what an action costs the planner:

* ``carried``: from the beliefs the robots carry at that point of the plan (the paper's
  semantic attachment, :mod:`tmpnav.attachment.carried`); the default;
* ``table``: every move from a canonical start state (:mod:`tmpnav.oracle.table`): the
  paper's cost table, faster, far off where landmarks are sparse.

``SEARCHES``, how the task plan is searched:

* ``exact``: one optimal ENHSP search (over the whole cost table, or over the unfolded belief
  space with carried costs);
* ``anytime``: large-neighbourhood search, ENHSP on sub-problems, with a certified lower bound;
* ``auto``: ``exact`` where it finishes quickly (:func:`exact_fits`), else ``anytime``.

``OBJECTIVES``, what the plan minimises (:mod:`tmpnav.task.objectives`):

* ``cost``: the paper's sum of action costs (the team's time does not count);
* ``weighted``: that sum plus ``cost.M_T`` per second of makespan;
* ``makespan``: the makespan first, the sum of action costs between plans as fast.

A scenario that names none gets :func:`default_objective`'s: ``makespan`` for a team on a shift
(robots back to their docks, or jobs with service times), else ``weighted``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

Costs = Literal["carried", "table"]
Search = Literal["auto", "exact", "anytime"]
SearchMode = Literal["exact", "anytime"]  # the search that runs (``auto`` resolved)
Objective = Literal["weighted", "cost", "makespan"]
#: where a robot may move to: the goal rooms it may serve, or every room (the oracle's modes)
Destinations = Literal["goals", "all-rooms"]
#: how a search ended: the exact search "solved"; the anytime search "optimal" (proved by its
#: bound or by one optimal search of the whole problem), "converged" (every neighbourhood tried
#: without improvement), "work budget" (its sub-problems spent: the same plan on any machine),
#: "time budget" (its time cap, or the run's time limit: a plan of the machine's speed), or
#: "nothing to do" (no move needed)
StopReason = Literal["solved", "optimal", "converged", "work budget", "time budget", "nothing to do"]

#: each stop reason as the summary says it
STOP_MEANINGS: dict[StopReason, str] = {
    "solved": "solved (one optimal search of the whole problem)",
    "optimal": "optimal (proved)",
    "converged": "converged (every neighbourhood tried without improvement: done)",
    "work budget": "work budget (its sub-problems spent, neighbourhoods left untried: --anytime-work may find a "
    "better plan)",
    "time budget": "time cap (neighbourhoods left untried when the time ran out: the plan depends on the "
    "machine's speed)",
    "nothing to do": "nothing to do",
}

COSTS: tuple[Costs, ...] = get_args(Costs)
SEARCHES: tuple[Search, ...] = get_args(Search)
SEARCH_MODES: tuple[SearchMode, ...] = get_args(SearchMode)
OBJECTIVES: tuple[Objective, ...] = get_args(Objective)
STOP_REASONS: tuple[StopReason, ...] = get_args(StopReason)


@dataclass(frozen=True)
class EncodingSpec:
    """What the scenario format and its checks know of an encoding (the encoding itself is
    :class:`tmpnav.task.encodings.Encoding`, registered under the same name)."""

    name: str
    doc: str  # one line, for --help and the reference
    destinations: Destinations
    pairs: bool  # are paired moves costed jointly by the oracle?


# fmt: off
ENCODINGS: dict[str, EncodingSpec] = {
    e.name: e
    for e in (
        EncodingSpec("paper", "the paper's goto_room for a pair of robots, both move in every action", "all-rooms", True),
        EncodingSpec("single", "one goto_room per robot, no mutual-observation credit", "goals", False),
        EncodingSpec("mixed", "single moves plus paired moves where mutual observations lower the joint cost", "goals", True),
    )
}
# fmt: on

#: ``auto`` plans exactly with table costs up to this many goal rooms with two robots (fewer
#: with more robots): the exact search costs every paired move first, about rooms^4 x robots^2
EXACT_ROOMS = 8

#: ``auto`` plans exactly with carried costs up to these sizes (goal rooms, robots): the
#: belief space is unfolded context by context (5 rooms, 2 robots: about 2,500 contexts)
EXACT_CARRIED = ((5, 2), (4, 3), (3, 4))

#: the default work budget of the anytime search: this many ENHSP sub-problems per goal room and
#: robot, clamped (the corridor's 10 rooms and 2 robots: 50, converged after 24; 20 rooms and 2
#: robots: 80, converged after 26; 40 rooms and 4 robots: 320, converged after 203). Counted in
#: work, not seconds, so that the same scenario gives the same plan on any machine, however busy
WORK_PER_ROOM_ROBOT = 2
WORK_RANGE = (50, 1000)


#: a replan's default work budget (tmpnav.replan): this share of the first plan's, at least
#: :data:`REPLAN_MIN_WORK` sub-problems. A team under way waits for its replan, and a replan
#: starts from the plan being executed: on the shipped buildings' random events
#: (benchmarks/bench_replan.py) the full budget found no better plan than a tenth of it
REPLAN_WORK_SHARE = 0.1
REPLAN_MIN_WORK = 10


def replan_work(rooms: int, robots: int, given: int | None) -> int:
    """A replan's work budget: :data:`REPLAN_WORK_SHARE` of the budget a first plan of this size
    has (``given``: the scenario's own), at least :data:`REPLAN_MIN_WORK` sub-problems."""
    return max(REPLAN_MIN_WORK, math.ceil(REPLAN_WORK_SHARE * work_budget(rooms, robots, given)))


def exact_fits(rooms: int, robots: int, costs: Costs) -> bool:
    """Does ``auto`` choose the exact search for this many goal rooms and robots?"""
    if costs == "carried":
        return any(rooms <= n and robots <= r for n, r in EXACT_CARRIED)
    return rooms <= EXACT_ROOMS and rooms * robots <= 2 * EXACT_ROOMS


def work_budget(rooms: int, robots: int, given: int | None) -> int:
    """The anytime search's work budget, in ENHSP sub-problems: ``given``, or by the problem's size."""
    if given is not None:
        return given
    low, high = WORK_RANGE
    return min(high, max(low, WORK_PER_ROOM_ROBOT * rooms * robots))


def time_budget(given: float | None) -> float:
    """The anytime search's time cap for a run: ``given`` (planner.time_budget), else none (inf):
    its work budget bounds it, and ``--time-limit`` the whole run."""
    return math.inf if given is None else given


@dataclass(frozen=True)
class TaskChoice:
    """The search and the costs a run plans with."""

    mode: SearchMode
    costs: Costs

    @property
    def lists_whole_table(self) -> bool:
        """Does this search cost every paired move before it starts? Only the exact search with
        table costs does; the others cost paired moves as their sub-problems ask."""
        return self.mode == "exact" and self.costs == "table"


def choose(encoding: str, search: Search, costs: Costs, rooms: int, robots: int, min_rooms: int = 0) -> TaskChoice:
    """The one rule that picks a run's search: the paper's encoding is the paper's model (the
    exact search with table costs); otherwise the search asked for, and for ``auto`` the exact
    search where it finishes quickly (:func:`exact_fits`) and no minimum of rooms per robot is
    asked for (``min_rooms``: only the anytime search keeps one, tmpnav.task.minimum)."""
    if encoding == "paper":
        return TaskChoice("exact", "table")
    if search == "auto":
        exact = exact_fits(rooms, robots, costs) and min_rooms <= 0
        return TaskChoice("exact" if exact else "anytime", costs)
    return TaskChoice(search, costs)


#: a team of this many robots or more is a fleet: it plans by default with the makespan first and
#: a minimum of FLEET_MIN_ROOMS goal rooms per robot (:func:`default_objective`, :func:`default_min_rooms`)
FLEET = 9
FLEET_MIN_ROOMS = 3


def default_objective(robots: int, shift: bool) -> Objective:
    """The objective of a scenario that names none: ``makespan`` for a team (two robots or more)
    on a ``shift`` -- some robot must end at its dock (``goals.ends``) or some job has a service
    time -- and for a fleet (:data:`FLEET` robots or more), else ``weighted``. On a shift the
    team's time is what its operator counts: the weighted objective's price of a second
    (``cost.M_T``) left a robot at its dock all shift where it could shorten the makespan by a
    fifth (benchmarks/README.md, "Objectives: a default that uses the team"); on tours of rooms
    without jobs it stays ``weighted``, whose price of time keeps robots out of stretches without
    landmarks at a small loss of makespan. A fleet's price of a second is worth as much whatever
    its size, so with 16 robots the weighted plans left 7-9 of them on fewer than 3 rooms and
    ended 5-59% after the makespan objective's (benchmarks/README.md, "Robots docked in a row
    under --objective makespan"); the shipped teams have at most 8."""
    return "makespan" if (robots >= 2 and shift) or robots >= FLEET else "weighted"


def default_min_rooms(robots: int) -> int:
    """The goal rooms each robot visits at least in a scenario that names no planner.min_rooms:
    :data:`FLEET_MIN_ROOMS` for a fleet, else none (0). With the makespan first, a fleet of 16
    robots on 100 rooms still left 2-6 of them on fewer than 3; held to the minimum, the search
    ended 5-11% sooner than the makespan objective alone, every robot on 3 rooms or more."""
    return FLEET_MIN_ROOMS if robots >= FLEET else 0


def paper_conflict(
    encoding: str, search: Search | None, costs: Costs | None, objective: Objective | None = None
) -> str | None:
    """Why a search, costs or objective asked for explicitly cannot go with ``encoding``, or
    None: the paper's encoding plans exactly with table costs, for the sum of action costs."""
    if encoding == "paper" and (costs == "carried" or search == "anytime"):
        return (
            "the paper's encoding is planned exactly with table costs; "
            "use --encoding mixed for --search anytime or --costs carried"
        )
    if encoding == "paper" and objective not in (None, "cost"):
        return "the paper's encoding minimises the sum of action costs; use --encoding mixed for --objective " + str(
            objective
        )
    return None
