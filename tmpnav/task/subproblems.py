"""A neighbourhood of the anytime search as a sub-problem for ENHSP (tmpnav.task.search, step 2).

The plan is opened around the neighbourhood (its robots' stretches of route cut out, the head
before them kept); the sub-problem is what those stretches achieved that is still to do after
the head, costed by the cost model from the robots' states at the head's end, with, where the
objective prices time or a job has a window, the team's clock at that point; and it is written
as PDDL text (tmpnav.task.pddl_text). Rooms no goal names may be passed through: a detour can be
cheaper than a direct move.
"""

from __future__ import annotations

from dataclasses import dataclass

from tmpnav.results import StageTimes
from tmpnav.task.model import CostModel, PlanCost
from tmpnav.task.model import entered as entered_by
from tmpnav.task.neighbourhoods import Neighbourhood
from tmpnav.task.pddl_text import Clocks, PddlTask, write_task
from tmpnav.task.plans import Cut, Plan, PlanError, Rules, State, cut
from tmpnav.types import Goals

#: paired moves a sub-problem offers ENHSP at most, those that save the largest share of their
#: two single moves (tmpnav.task.encodings.strongest_pairs). Without a lidar two robots that see
#: each other save much, and a sub-problem holding both offered up to 300-370 paired moves (1 MB
#: of PDDL, four actions each where time is priced), which ENHSP parses and grounds for most of
#: a search's time. On the generated landmark-only offices (24 rooms and 2 robots, seeds 1-5;
#: 10 rooms, seed 2; 40 rooms and 4 robots, seeds 1-2) every plan that improved on another used
#: paired moves among the 40 that save most, and the runs took 10-30% less
#: (benchmarks/landmark_family/); 20 lost two of those improvements.
SUB_PAIRS = 40


@dataclass(frozen=True)
class Sub:
    """A neighbourhood's sub-problem, ready for ENHSP."""

    hood: Neighbourhood
    opened: Cut
    task: PddlTask


@dataclass(frozen=True)
class Encoding:
    """How sub-problems are written: the PDDL encoding, a paired move's least gain, and the
    objective's price of a second of makespan (tmpnav.task.objectives)."""

    name: str
    min_gain: float
    span_weight: float


class SubProblems:
    """The sub-problems of one search: its model, goals, rules and encoding; ``waypoints`` are the
    rooms no goal names that a sub-problem may pass through (set once the single moves are known)."""

    def __init__(self, model: CostModel, goals: Goals, rules: Rules, encoding: Encoding, times: StageTimes):
        self.model, self.goals, self.rules, self.encoding, self.times = model, goals, rules, encoding, times
        self.waypoints: tuple[str, ...] = ()

    def of(self, plan: Plan, hood: Neighbourhood, best: PlanCost, every_pair: bool = False) -> Sub | None:
        """The sub-problem of ``hood`` in ``plan`` (whose cost, with its schedule, is ``best``): the
        plan opened, its goals, its costs, its PDDL text (with the :data:`SUB_PAIRS` paired moves
        that save most; ``every_pair``: all that save the encoding's least gain); None when the
        head is not a valid plan."""
        opened = cut(plan, set(hood.removed), set(hood.robots))
        try:
            head_state = self.rules.run(opened.head)
        except PlanError:
            return None
        goals = self.goals_of(plan, hood, head_state)
        entered = {m[2] for step in plan for m in step}
        free = [x for x in self.waypoints if x not in entered or x in hood.rooms]
        dropped = [x for x in goals.visit if x not in hood.rooms]  # optional goals left undone, to take up
        enc, most_pairs = self.encoding, None if every_pair else SUB_PAIRS
        with self.times.timed("oracle"):
            table = self.model.subtable(opened.head, hood.robots, (*hood.rooms, *dropped, *free), goals)
            clocks = self.clocks(opened, hood, best) if enc.span_weight or self.goals.windows else None
        with self.times.timed("encode"):
            task = write_task(
                table, goals, enc.name, "sub", enc.min_gain, hood.ends, enc.span_weight, clocks, most_pairs
            )
        return Sub(hood, opened, task)

    def clocks(self, opened: Cut, hood: Neighbourhood, best: PlanCost) -> Clocks:
        """Where the team's clock stands for a sub-problem: each of its robots free when its moves
        before the sub-problem end, plus the time its moves after it take (they follow what the
        sub-problem gives it); the span, the end of the other robots' moves in the current plan
        (``best``'s schedule)."""
        schedule = best.schedule
        if schedule is None:
            return Clocks()
        ends = self.model.ends(opened.head)
        start = {}
        for r in hood.robots:
            timeline = schedule.timeline(r)
            last = max((m.done for m in timeline if m.step in hood.removed), default=ends[r])
            start[r] = ends[r] + max(0.0, max((m.done for m in timeline), default=0.0) - last)
        others = [m.done for m in schedule.moves if m.robot not in hood.robots]
        return Clocks(start, max(others, default=0.0))

    def goals_of(self, plan: Plan, hood: Neighbourhood, state: State) -> Goals:
        """What the opened moves achieved that is still to do after the head."""
        visit: list[str] = []
        per_robot: dict[str, list[str]] = {}
        ends: list[tuple[str, str]] = []
        # the optional goals the plan leaves undone: each sub-problem may take one up again
        visit += [x for x in self.goals.dropped(entered_by(plan, self.model.start_location)) if x not in state.visited]
        for k in sorted(hood.removed):
            for r, _, x in plan[k]:
                if r not in hood.robots:
                    continue
                if x in self.goals.visit and x not in state.visited:
                    visit.append(x)  # an optional goal too: the sub-problem may leave it undone
                if (r, x) in self.rules.targets and (r, x) not in state.visited_by:
                    per_robot.setdefault(r, []).append(x)
                if self.goals.end_of(r) == x and r not in hood.ends:  # its end is among its opened moves
                    ends.append((r, x))
        return Goals(
            tuple(dict.fromkeys(visit)),
            tuple((r, tuple(xs)) for r, xs in per_robot.items()),
            self.goals.jobs,
            tuple(dict.fromkeys(ends)),
        )
