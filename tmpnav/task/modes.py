"""The task stage's choices, for the scenario format and the command line (no planning imports).

``SEARCHES``: how the task plan is searched (:func:`tmpnav.task.stage` and :mod:`tmpnav.pipeline`):

* ``exact``: one optimal ENHSP search over the whole cost table, every paired move costed first;
* ``anytime``: :mod:`tmpnav.task.search`, ENHSP on sub-problems, with a certified lower bound;
* ``auto``: ``exact`` where it finishes quickly (few rooms and robots), else ``anytime``.

``COSTS``: what an action costs the planner:

* ``table``: every move from a canonical start state (:mod:`tmpnav.oracle.table`);
* ``carried``: from the beliefs the robots carry at that point of the plan (:mod:`tmpnav.attachment.carried`).
"""

SEARCHES = ("auto", "exact", "anytime")
COSTS = ("carried", "table")

#: ``auto`` plans exactly with table costs up to this many goal rooms with two robots (fewer
#: with more robots): the exact search costs every paired move first, about rooms^4 x robots^2
EXACT_ROOMS = 8

#: ``auto`` plans exactly with carried costs up to these sizes (goal rooms, robots): the
#: belief space is unfolded context by context (5 rooms, 2 robots: about 2,500 contexts)
EXACT_CARRIED = ((5, 2), (4, 3), (3, 4))


def exact_fits(rooms: int, robots: int, costs: str = "table") -> bool:
    """Does ``auto`` choose the exact search for this many goal rooms and robots?"""
    if costs == "carried":
        return any(rooms <= n and robots <= r for n, r in EXACT_CARRIED)
    return rooms <= EXACT_ROOMS and rooms * robots <= 2 * EXACT_ROOMS


#: the default time budget of the anytime search: this many seconds per goal room and robot,
#: clamped (20 rooms and 2 robots: 10 s; 40 and 4: 40 s; 60 and 8: 120 s)
BUDGET_PER_ROOM_ROBOT = 0.25
BUDGET_RANGE = (10.0, 180.0)


def time_budget(rooms: int, robots: int, given: float | None) -> float:
    """The anytime search's budget for a run: ``given``, or by the problem's size."""
    if given is not None:
        return given
    low, high = BUDGET_RANGE
    return min(high, max(low, BUDGET_PER_ROOM_ROBOT * rooms * robots))
