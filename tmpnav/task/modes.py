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
COSTS = ("table", "carried")

#: ``auto`` plans exactly up to this many goal rooms with two robots (fewer with more robots):
#: the exact search costs every paired move first, about rooms^4 x robots^2 of them
EXACT_ROOMS = 8


def exact_fits(rooms: int, robots: int) -> bool:
    """Does ``auto`` choose the exact search for this many goal rooms and robots?"""
    return rooms <= EXACT_ROOMS and rooms * robots <= 2 * EXACT_ROOMS
