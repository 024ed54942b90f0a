"""What a planning run returns: the task stage's result and the pipeline's report.

``TaskResult`` is what every task planner returns (:data:`tmpnav.planning.PLANNERS`: the ordered
plan steps, their costs as the planner saw them, how big the task problem was, whether the plan
came from the cache); ``PlanReport`` is what :func:`tmpnav.pipeline.plan` returns and every
writer of ``report/`` reads (plan.json, the terminal summary, plan.png). Both are plain typed
values: the report code reads attributes, never dictionary keys, and this module imports no
class of the oracle or the task stage (it sits below them: they return its values).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from tmpnav.choices import COSTS, SEARCH_MODES, STOP_REASONS, Costs, SearchMode, StopReason
from tmpnav.types import (
    WINDOW_TOL,
    CostTable,
    MoveKey,
    PlannedAction,
    PlanStatus,
    Roadmap,
    Scenario,
    TrajectoryStep,
)

if TYPE_CHECKING:  # annotations only: the world is stage 2, built before this module's values
    from tmpnav.world import World

#: a JSON value (plan.json, cache entries), as the standard library's ``json`` reads and writes it
JSON = dict[str, "JSON"] | list["JSON"] | str | int | float | bool | None

#: progress of the anytime search: (seconds since the run started, best plan cost, lower
#: bound or None, what happened)
SearchProgress = Callable[[float, float, float | None, str], None]

_Name = TypeVar("_Name", bound=str)

#: the pipeline's stages in the order they run; a run's ``total`` is all of them but ``load``.
#: In the anytime search the stages interleave: ``oracle`` counts the costs it asks for,
#: ``encode`` and ``planner`` its sub-problems, ``bound`` the lower bound.
STAGES = ("load", "roadmap", "oracle", "encode", "planner", "bound", "resimulate")
#: the run's time in no stage: starting and closing the oracle's workers, the steps between stages
OTHER = "other"


@dataclass
class StageTimes:
    """Seconds spent in each stage of a run (keys of :data:`STAGES`), filled in as it runs, and
    the run's clock (:meth:`elapsed`), started when the run starts.

    A stage timed inside another (the oracle asked for costs while the planner's time runs) is
    counted once, in the inner stage: the outer one's clock stops meanwhile. So the stages never
    add up to more than the run's wall-clock time, and :meth:`close` records the rest as
    :data:`OTHER`: every stage but ``load``, and ``other``, add up to ``total``."""

    seconds: dict[str, float] = field(default_factory=dict)
    started: float = field(default_factory=lambda: time.perf_counter(), compare=False, repr=False)
    #: the stages timed now, the innermost last, each with when its clock last started
    _open: list[tuple[str, float]] = field(default_factory=list, compare=False, repr=False)

    def elapsed(self) -> float:
        """Wall-clock seconds of the run so far, less ``load`` (the scenario read and the world
        built, before anything else): the one clock of its progress, which ``total`` ends."""
        return time.perf_counter() - self.started - self.seconds.get("load", 0.0)

    def add(self, stage: str, dt: float) -> None:
        self.seconds[stage] = self.seconds.get(stage, 0.0) + dt

    @contextmanager
    def timed(self, stage: str) -> Iterator[None]:
        """Add the wall-clock time of the ``with`` block to ``stage``, less the time of the stages
        timed inside it."""
        now = time.perf_counter()
        if self._open:  # the enclosing stage's clock stops
            outer, since = self._open[-1]
            self.add(outer, now - since)
        self._open.append((stage, now))
        try:
            yield
        finally:
            now = time.perf_counter()
            _, since = self._open.pop()
            self.add(stage, now - since)
            if self._open:  # and starts again
                self._open[-1] = (self._open[-1][0], now)

    def spent(self) -> float:
        """Seconds of every stage so far but ``load`` (scenario parsing and world building):
        what a run's time budget counts."""
        return sum(v for k, v in self.seconds.items() if k not in ("load", "total", OTHER))

    def close(self) -> None:
        """Record ``total``, the run's wall-clock time but ``load`` (:meth:`elapsed`), and as
        ``other`` the part of it in no stage, once the run is done."""
        total = self.elapsed()
        self.seconds[OTHER] = max(0.0, total - self.spent())
        self.seconds["total"] = self.spent() + self.seconds[OTHER]


@dataclass(frozen=True)
class TimedMove:
    """One robot's move on the team's clock: when it could start, when it started, when it ended.

    A robot is ``ready`` when its previous move ends (0 for its first); a paired move starts
    when both robots are ready, so the earlier one waits (``start - ready``); a move may also
    be held back to keep clear of another robot. Seconds from the start of the plan."""

    step: int  # the plan step (0-based) the move belongs to
    robot: str
    origin: str
    target: str
    partner: str | None  # the other robot of a paired move
    ready: float
    start: float
    end: float  # when it arrives
    service: float = 0.0  # seconds it then stands at the target for the room's job (goals.jobs)
    opens: float = 0.0  # seconds it waits at the target, before its service, for the job's window to open

    @property
    def wait(self) -> float:
        """Seconds the robot waits before this move starts."""
        return self.start - self.ready

    @property
    def done(self) -> float:
        """When the robot is free again: its arrival, the wait for the job's window, its service time."""
        return self.end + self.opens + self.service


@dataclass(frozen=True)
class Schedule:
    """The plan as the team runs it: every robot's moves on one clock, all robots at once."""

    robots: tuple[str, ...]
    moves: tuple[TimedMove, ...]  # in plan order; a paired step has one entry per robot

    @property
    def makespan(self) -> float:
        """When the last move ends, its job's service included (0 for a plan without moves)."""
        return max((m.done for m in self.moves), default=0.0)

    def timeline(self, robot: str) -> tuple[TimedMove, ...]:
        """The robot's moves in the order it makes them."""
        return self._timelines.get(robot, ())

    @functools.cached_property
    def _timelines(self) -> dict[str, tuple[TimedMove, ...]]:
        """Robot -> its moves in plan order, for :meth:`timeline` (asked for every robot of every
        plan the search prices)."""
        found: dict[str, list[TimedMove]] = {}
        for m in self.moves:
            found.setdefault(m.robot, []).append(m)
        return {r: tuple(ms) for r, ms in found.items()}

    def busy(self, robot: str) -> float:
        """Seconds the robot drives."""
        return sum(m.end - m.start for m in self.timeline(robot))

    def idle(self, robot: str) -> float:
        """Seconds of the makespan the robot neither drives, waits for a move nor serves a job:
        the time after its last move, so that busy + waits + service + idle = makespan."""
        return max(0.0, self.makespan - self.busy(robot) - self.waits(robot) - self.service(robot))

    def service(self, robot: str) -> float:
        """Seconds the robot stands at stations for their jobs (goals.jobs)."""
        return sum(m.service for m in self.timeline(robot))

    def waits(self, robot: str) -> float:
        """Seconds the robot waits between its moves (and at a station for its window to open)."""
        return sum(m.wait + m.opens for m in self.timeline(robot))

    def late(self, windows: Mapping[str, tuple[float, float]]) -> tuple[TimedMove, ...]:
        """The moves that arrive after their target's window closes (goals.jobs)."""
        return tuple(m for m in self.moves if m.target in windows and m.end > windows[m.target][1] + WINDOW_TOL)


@dataclass(frozen=True)
class KeptApart:
    """How a plan under a chance constraint was kept clear of robots in each other's way
    (tmpnav.attachment.apart.keep_apart): the conflicts of the plan as planned and left,
    the waits (plan step, 1-based, and seconds held back), the sidesteps (robot, origin,
    siding room, target), the plan as planned run on the clock (its executed cost and
    makespan), the clock runs the search made, and the detours (plan step, robot, metres
    driven more than the shortest path)."""

    conflicts_before: int
    conflicts_left: int
    waits: tuple[tuple[int, float], ...]
    sidesteps: tuple[tuple[str, str, str, str], ...]
    cost_before: float
    makespan_before: float
    runs: int
    detours: tuple[tuple[int, str, float], ...] = ()  # (plan step, 1-based; robot; metres longer)


@dataclass(frozen=True)
class TaskCounts:
    """How big the task problem was (plan.json ``task``)."""

    single_moves: int  # cost-table entries of one robot moving alone
    pair_moves_evaluated: int  # pairs of moves the oracle costed jointly
    actions: int  # actions of the task problem
    pair_actions: int  # grounded paired actions kept in the problem
    reshaped_rooms: int  # rooms with a cost-reshaping potential


@dataclass(frozen=True)
class SearchSummary:
    """How the task plan was found (plan.json ``search``)."""

    mode: SearchMode  # "exact": one optimal ENHSP search; "anytime": tmpnav.task.search
    costs: Costs  # "table" (canonical start states) | "carried" (the beliefs the robots carry)
    stopped: StopReason  # exact: "solved"; anytime: "optimal" | "converged" | "work budget" | "time budget" | ...
    start: str = ""  # anytime: how the first plan was found
    subproblems: int = 0  # anytime: sub-problems ENHSP solved
    improvements: int = 0  # anytime: plans kept because they were cheaper
    seconds: float = 0.0  # the search's own time
    history: tuple[tuple[float, float], ...] = ()  # (seconds, best cost) at each improvement
    work: int | None = None  # anytime: its work budget, in sub-problems (tmpnav.task.budget)
    #: anytime: the time caps that cut something short (the search's, OR-Tools', a sub-problem's):
    #: empty when the plan is the same on any machine
    capped: tuple[str, ...] = ()

    def to_json(self) -> dict[str, JSON]:
        """As plan.json's ``search`` (and the remembered plans) hold it."""
        return {
            "mode": self.mode,
            "costs": self.costs,
            "stopped": self.stopped,
            "start": self.start,
            "subproblems": self.subproblems,
            "improvements": self.improvements,
            "seconds": self.seconds,
            "history": [[t, c] for t, c in self.history],
            "work_budget": self.work,
            "capped": list(self.capped),
        }

    @staticmethod
    def from_json(entry: dict[str, JSON]) -> SearchSummary:
        """The summary :meth:`to_json` wrote; KeyError, TypeError or ValueError when it is not one."""
        history = entry["history"]
        if not isinstance(history, list):
            raise TypeError("history")
        return SearchSummary(
            _one_of(entry["mode"], SEARCH_MODES),
            _one_of(entry["costs"], COSTS),
            _one_of(entry["stopped"], STOP_REASONS),
            str(entry["start"]),
            int(_number(entry["subproblems"])),
            int(_number(entry["improvements"])),
            _number(entry["seconds"]),
            tuple(_pair(h) for h in history),
            None if entry.get("work_budget") is None else int(_number(entry["work_budget"])),
            tuple(str(c) for c in _list(entry.get("capped", []))),
        )


@dataclass(frozen=True)
class BoundSummary:
    """A certified lower bound on the cost of every plan of the plan space (plan.json ``bound``)."""

    value: float
    relaxation: str  # what proved it: "exact" (ENHSP's optimal search), "flow", "assignment", ...
    gap: float  # (plan cost - bound) / plan cost
    proved_optimal: bool

    def against(self, objective: float) -> BoundSummary:
        """The same bound against a plan changed after the search (kept apart: waits, detours and
        split pairs the bound's plan space does not hold), of objective value ``objective``: its
        gap, clipped at 0, and no proof of optimality."""
        gap = max(0.0, (objective - self.value) / objective) if objective > 0.0 else 0.0
        return BoundSummary(self.value, self.relaxation, gap, False)


@dataclass(frozen=True)
class TaskResult:
    """The task stage's answer: the plan's steps in canonical order, with their table costs."""

    status: PlanStatus
    engine: str  # the engine that solved the problem (unified-planning's name for it)
    steps: tuple[tuple[MoveKey, ...], ...]  # each step: the moves of the 1 or 2 robots it moves
    action_names: tuple[str, ...]  # the planner's action name of each step
    step_costs: tuple[float, ...]  # each step's cost in the cost table, as the planner saw it
    counts: TaskCounts
    plan_hit: bool  # the plan was remembered for this exact problem; nothing was encoded or solved
    search: SearchSummary | None = None
    bound: BoundSummary | None = None
    #: the steps on the team's clock as the planner saw them (None for a table without durations)
    schedule: Schedule | None = None
    #: the PDDL domain and problem the planner solved, written on demand; None when the plan was
    #: remembered or found by a search over sub-problems (tmpnav.pipeline.pddl_texts encodes it then)
    pddl: Callable[[], tuple[str, str]] | None = field(default=None, repr=False, compare=False)

    @property
    def planner_cost(self) -> float:
        return float(sum(self.step_costs))

    @property
    def makespan(self) -> float | None:
        """When the team ends the plan as the planner saw it (None without durations)."""
        return self.schedule.makespan if self.schedule is not None else None


@dataclass(frozen=True)
class CacheUse:
    """What the disk cache did during a run (plan.json ``cache``)."""

    enabled: bool
    directory: Path | None
    hits: int  # oracle requests answered from the cache
    misses: int  # oracle requests computed
    roadmap_hit: bool  # the roadmap was loaded instead of grown
    table_hit: bool  # the whole cost table was loaded
    plan_hit: bool  # the task plan was remembered
    warnings: tuple[str, ...] = ()  # damaged cache files set aside, entries recomputed


@dataclass(frozen=True)
class OracleCounts:
    """What the cost oracle did during a run (plan.json ``oracle``)."""

    table_cache_hit: bool  # the whole cost table was loaded
    requests: int
    cache_hits: int
    cache_misses: int
    single_simulations: int
    joint_simulations: int
    joint_factorized: int  # pairs that never saw each other: sums of single simulations
    pairs_pruned: int  # pairs proved unable to save pair_min_gain, never simulated jointly

    def as_dict(self) -> dict[str, int | bool]:
        return dict(vars(self))


@dataclass(frozen=True)
class Revision:
    """What a revised plan is: its number, when its clock starts on the first plan's, and what the
    state changed (plan.json ``revision``)."""

    number: int
    start_time: float  # s on the team's clock of the first plan (revision 0)
    previous: str  # the plan.json it revises
    done: tuple[str, ...]  # goal rooms done before it
    down: tuple[str, ...]  # robots out of the team
    unreachable: tuple[tuple[str, str], ...]  # (room, why) goals no robot can reach any more
    #: the rest of the old plan: steps of (robot, target) pairs, the search's incumbent
    incumbent: tuple[tuple[tuple[str, str], ...], ...] = ()
    #: (robot, room, s): a robot at its station when the revision starts, held there for the rest
    #: of its wait and service (Goals.held)
    held: tuple[tuple[str, str, float], ...] = ()
    #: what decided the plan: "search" (the planner), or "repair" (the rest of the old plan with
    #: the goals of robots down inserted where they cost least, when the search found no plan)
    rule: str = "search"
    #: (door, open) of every door whose state differs from the scenario's in this revision: the
    #: state's and those an earlier revision changed, which a revision of it keeps
    doors: tuple[tuple[str, bool], ...] = ()


@dataclass(frozen=True)
class PlanReport:
    """Everything ``tmpnav plan`` reports (the JSON schema is docs/plan-json.md)."""

    scenario: Scenario  # with the command line's overrides applied
    world: World
    roadmap: Roadmap
    table: CostTable  # the costs the task planner saw
    task: TaskResult
    actions: tuple[PlannedAction, ...]  # the plan's steps, re-simulated with carried-over beliefs
    trajectories: dict[str, list[TrajectoryStep]]  # robot -> belief at every control step
    schedule: Schedule  # the re-simulated plan on the team's clock
    times: StageTimes
    cache: CacheUse
    oracle: OracleCounts
    #: waits and sidesteps that keep the robots apart, under a chance constraint (None: none applied)
    apart: KeptApart | None = None
    #: what this plan revises, for a plan made by ``tmpnav replan`` (None: a first plan)
    revision: Revision | None = None

    @property
    def encoding(self) -> str:
        return self.scenario.planner.encoding

    @property
    def planner(self) -> str:
        return self.scenario.planner.name

    @property
    def status(self) -> PlanStatus:
        return self.task.status

    @property
    def planner_cost(self) -> float:
        return self.task.planner_cost

    @property
    def resimulated_cost(self) -> float:
        return float(sum(a.resimulated_cost for a in self.actions))

    @property
    def worst_risk(self) -> float:
        """The largest collision bound of any move (docs/models.md, "Collision bound")."""
        return max((p for a in self.actions for p in a.risk), default=0.0)

    @property
    def risk(self) -> float:
        """The plan's collision bound: its moves' bounds summed (Boole's inequality), at most 1."""
        return min(1.0, sum(p for a in self.actions for p in a.risk))

    def largest_std(self) -> dict[str, float]:
        """Each robot's largest position standard deviation along the plan (m): the square
        root of the largest eigenvalue of its position covariance at any control step."""
        out = {}
        for robot, steps in self.trajectories.items():
            worst = 0.0
            for step in steps:
                (a, b, _), (_, d, _) = step.cov[0], step.cov[1]
                worst = max(worst, 0.5 * (a + d) + math.sqrt(0.25 * (a - d) ** 2 + b * b))
            out[robot] = math.sqrt(worst)
        return out


def _one_of(value: JSON, choices: tuple[_Name, ...]) -> _Name:
    for choice in choices:
        if value == choice:
            return choice
    raise ValueError(f"{value!r} is not one of {choices}")


def _number(value: JSON) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"{value!r} is not a number")
    return float(value)


def _pair(value: JSON) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise TypeError(f"{value!r} is not a pair of numbers")
    return _number(value[0]), _number(value[1])


def _list(value: JSON) -> list[JSON]:
    if not isinstance(value, list):
        raise TypeError(f"{value!r} is not a list")
    return value
