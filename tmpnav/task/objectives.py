"""What a plan minimises: the objectives, as a registry (their names are in tmpnav.choices).

Every objective is the sum of the plan's action costs (the paper's c = M_u c_u + M_G c_G +
M_Sigma c_Sigma of every move, as the cost model gives them) plus a price on the team's time,
``span_weight`` cost units per second of makespan (the time the last robot ends its last
move, all robots moving at once: :mod:`tmpnav.task.timing`, :mod:`tmpnav.attachment.clock`):

* ``cost``: no price on time, the paper's objective (the plans of tmpnav before schedules);
* ``weighted``: ``cost.M_T`` per second, so that a team is not left idle for a cheaper sum;
* ``makespan``: :data:`MAKESPAN_WEIGHT` per second, so large that the fastest plan wins and the
  sum only decides between plans as fast (one control step of makespan outweighs any sum of
  action costs tmpnav meets).

Being linear in the makespan, every objective is what the searches minimise in the same way:
OR-Tools' routes with a global span cost, ENHSP with the robots' clocks in the problem
(:mod:`tmpnav.task.pddl_text`), and the anytime search comparing plans by :meth:`Objective.value`.
A new objective is a name in tmpnav.choices and an entry here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from tmpnav.choices import Objective as Name
from tmpnav.types import PENALISED, CostWeights

#: cost units per second of makespan in the ``makespan`` objective
MAKESPAN_WEIGHT = 1.0e4


def strict_price(span_weight: float) -> float:
    """What the searches add to a plan's objective for each thing that ranks it below every plan
    without, under the objective of ``span_weight``: a conflict left (a plan ``tmpnav plan``
    refuses), a room a robot lacks of planner.min_rooms. PENALISED cost units, more than any sum
    of action costs tmpnav meets, and PENALISED seconds of makespan where a second is priced above
    a unit (``makespan``): a price of PENALISED units alone would be worth only 100 s there, and a
    plan 100 s shorter would rank above a plan kept apart."""
    return PENALISED * max(1.0, span_weight)


@dataclass(frozen=True)
class Objective:
    """An objective: the sum of action costs plus ``span_weight(weights)`` per second of makespan."""

    name: Name
    doc: str
    span_weight: Callable[[CostWeights], float]
    #: its own units: ``cost`` (unit-less, as the action costs) or ``s`` (the makespan's seconds)
    units: str = "cost"

    def value(self, cost: float, makespan: float, weights: CostWeights) -> float:
        """The objective of a plan whose actions cost ``cost`` in all and which ends at ``makespan`` s."""
        w = self.span_weight(weights)
        return cost + w * makespan if w else cost

    def own(self, value: float, dt: float) -> float:
        """A value of :meth:`value`, a plan's or a lower bound's, in the objective's own units.

        In cost units it is the value itself. In seconds (``makespan``) it is the makespan on
        the clock's grid of ``dt`` s that the value implies: a plan's cost + W m, with its sum of
        costs below W dt, gives its makespan m; a lower bound B on cost + W m over every plan
        gives m >= dt floor(B / (W dt)), a lower bound on the makespan. W is MAKESPAN_WEIGHT."""
        if self.units == "cost" or not math.isfinite(value):
            return value
        w = MAKESPAN_WEIGHT
        return dt * math.floor(value / (w * dt) + 1e-9)


OBJECTIVES: dict[Name, Objective] = {
    o.name: o
    for o in (
        Objective("weighted", "the sum of action costs plus cost.M_T per second of makespan", lambda w: w.M_T),
        Objective("cost", "the paper's sum of action costs; the team's time does not count", lambda w: 0.0),
        Objective("makespan", "the makespan first, then the sum of action costs", lambda w: MAKESPAN_WEIGHT, units="s"),
    )
}
