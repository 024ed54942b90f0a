"""Replanning from where the team is (``tmpnav replan``, docs/replan.md): the state file
(:mod:`tmpnav.replan.state`), the revised scenario (:mod:`tmpnav.replan.revise`) and the run
that plans it, the rest of the old plan as the search's incumbent."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tmpnav.errors import InputError, WindowError
from tmpnav.replan.revise import Revision, leave_out, revise
from tmpnav.replan.state import TeamState, read_state
from tmpnav.results import PlanReport, SearchProgress
from tmpnav.types import Roadmap, Scenario
from tmpnav.world import World

if TYPE_CHECKING:
    from tmpnav.pipeline import PlanOptions as Options

__all__ = ["Revision", "Session", "TeamState", "nav2_files", "read_plan", "read_state", "replan"]


def read_plan(path: Path) -> dict[str, Any]:
    """A plan.json written by ``tmpnav plan`` (or ``tmpnav replan``); InputError otherwise."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise InputError(f"{path}: cannot read the plan: {err.strerror or err}") from None
    except json.JSONDecodeError as err:
        raise InputError(
            f"{path}: not a plan.json ({err.msg} at line {err.lineno}); expected tmpnav plan's plan.json"
        ) from None
    if not isinstance(doc, dict):
        raise InputError(f"{path}: not a plan.json; expected tmpnav plan's plan.json")
    return doc


def replan(
    scenario_path: str | Path,
    plan_path: str | Path,
    state: str | Path | TeamState,
    options: Options | None = None,
    loaded: tuple[Scenario, World] | None = None,
) -> PlanReport:
    """The plan of the rest of the work, from the team's state: the scenario revised
    (:func:`tmpnav.replan.revise.revise`) and planned as ``tmpnav plan`` plans, the rest of the
    old plan as the anytime search's incumbent; the report carries the revision. ``loaded``
    (:func:`tmpnav.pipeline.load_world` of the scenario, with the options' overrides) skips
    loading when the caller already has the world, as a planning service has."""
    from tmpnav import pipeline

    options = options or pipeline.PlanOptions()
    team = state if isinstance(state, TeamState) else read_state(Path(state))
    doc = read_plan(Path(plan_path))
    loaded = loaded or pipeline.load_world(scenario_path, options.overrides)
    return _revised(scenario_path, loaded, Path(plan_path), doc, team, options)


def _revised(
    scenario_path: str | Path,
    loaded: tuple[Scenario, World],
    plan_path: Path,
    doc: dict[str, Any],
    team: TeamState,
    options: Options,
    incumbent: tuple[tuple[tuple[str, str], ...], ...] | None = None,
    within: bool = True,
) -> PlanReport:
    from tmpnav import pipeline
    from tmpnav.world.build import build

    scenario, world = loaded

    def world_of(revised: Scenario | None) -> World:
        return world if revised is None else build(revised)

    revised, new_world, revision = revise(scenario, world_of, plan_path, doc, team, within)
    if incumbent is not None:  # the caller knows the rest of the work better than the plan's clock
        wanted, live = set(revised.goals.all_rooms), {r.name for r in revised.robots}
        kept = (tuple((r, x) for r, x in step if x in wanted and r in live) for step in incumbent)
        revision = replace(revision, incumbent=tuple(step for step in kept if step))
    # the world unchanged (no door opened or closed) and no station added: the plan's roadmap with
    # the robots' starts added
    same = new_world is world and set(revised.roadmap.poses) <= set(scenario.roadmap.poses)
    base = _grown(scenario, world, options) if same else None
    search = _search_of(revised, options)
    revised_options = options.but(
        incumbent=revision.incumbent,
        roadmap_base=base,
        origins=scenario.robots,
        search_progress=_against_budget(
            options.reporters.search, search.get("time_budget", options.overrides.time_budget)
        ),
        **search,
    )
    while True:
        try:
            report = pipeline.plan(scenario_path, revised_options, loaded=(revised, new_world))
        except WindowError as err:
            if not (err.certain and err.room in revised.goals.all_rooms):
                raise _on_first_clock(err, revision, scenario) from None
            # no robot can get there in time: out of reach, as a goal whose window closed before
            t0 = revision.start_time
            why = (
                f"its window closes at {err.latest + t0:g} s, before any robot allowed there can arrive "
                f"(at the earliest {err.arrival + t0:.1f} s)"
            )
            revised, revision = leave_out(revised, revision, err.room, why, team)
            revised_options = revised_options.but(incumbent=revision.incumbent)
            continue
        return replace(report, revision=replace(revision, rule=_rule(report)))


def _rule(report: PlanReport) -> str:
    """What decided a revision: "repair" when its plan is the rest of the old plan with the goals
    left by robots down (and added) inserted where they cost least within their windows, the
    search's first plan, which it found nothing better than; else "search"."""
    from tmpnav.task.search import UNDER_WAY

    search = report.task.search
    return "repair" if search is not None and search.start == UNDER_WAY and search.improvements == 0 else "search"


def _on_first_clock(err: WindowError, revision: Revision, scenario: Scenario) -> WindowError:
    """A revision's window error with its times on the first plan's clock, where the scenario
    gives the windows (and on the revision's, from its start)."""
    if not err.room:
        return err
    t0 = revision.start_time
    arrival = "never" if math.isinf(err.arrival) else f"at {err.arrival + t0:.1f} s ({err.arrival:.1f} s into it)"
    return WindowError(
        f"{scenario.source.name}: goals.jobs.{err.room}.window: it closes at {err.latest + t0:g} s on the first "
        f"plan's clock ({err.latest:g} s into revision {revision.number}, which starts at {t0:g} s), and the "
        f"earliest arrival found is {arrival}; no plan found meets every window; expected a window that closes "
        "later, another robot allowed to do the job, or the goal removed (goals.remove)",
        err.room,
        err.latest + t0,
        err.arrival + t0,
    )


def _search_of(revised: Scenario, options: Options) -> dict[str, Any]:
    """A replan's search, unless the options name one: the anytime search from the plan being
    executed (``auto`` would plan a few rooms left exactly, which takes longer than the whole
    replan: 5.5 s for 3 rooms and 4 robots), with :func:`tmpnav.choices.replan_work`."""
    from tmpnav.choices import replan_work

    out: dict[str, Any] = {}
    sp = revised.planner
    if options.overrides.search is None and sp.search == "auto" and sp.encoding != "paper":
        out["search"] = "anytime"
    if options.overrides.work_budget is None:
        out["work_budget"] = replan_work(len(revised.goals.all_rooms), len(revised.robots), sp.work_budget)
    return out


def _against_budget(progress: SearchProgress | None, budget: float | None) -> SearchProgress | None:
    """The search's progress, each event saying how much of the run's budget the run had spent
    by then: the budget counts from the run's start, and the stages before the search (the
    roadmap with the new starts, the moves from them) and its first plan are made whatever it
    is, so a replan may pass it before the search improves anything (docs/replan.md)."""
    if progress is None or budget is None:
        return progress
    tell = progress

    def told(seconds: float, best: float, bound: float | None, what: str) -> None:
        tell(seconds, best, bound, f"{what}; the run at {seconds:.1f} s of its budget of {budget:g} s")

    return told


#: the roadmaps of the plans being revised, by their store key: a service revising one plan
#: again and again reads it once
_GROWN: dict[str, Roadmap] = {}


def _grown(scenario: Scenario, world: World, options: Options) -> Roadmap:
    """The roadmap the scenario's first plan was made on (the robots at their starts): from
    the cache, else grown as ``tmpnav plan`` grows it."""
    from tmpnav import pipeline
    from tmpnav.cachedir import CacheDir
    from tmpnav.roadmap.store import RoadmapStore, roadmap_key

    key = roadmap_key(world, scenario.robots, scenario.roadmap)
    if key not in _GROWN:
        run = options.execution
        cache = CacheDir.at(run.cache_dir) if run.use_cache else None
        if cache is not None:
            cache.ensure()
        store = RoadmapStore(cache) if cache is not None else None
        _GROWN[key] = pipeline.roadmap_for(scenario, world, store)[0]
        while len(_GROWN) > 2:
            _GROWN.pop(next(iter(_GROWN)))
    return _GROWN[key]


def nav2_files(report: PlanReport) -> dict[str, str]:
    """The nav2 export of a plan (tmpnav.export.nav2) with the revision's number in every file
    name (``r1.moves.rev2.yaml``, and ``schedule.rev2.yaml`` naming those; a first plan's names as
    ``tmpnav plan --export nav2`` writes them): what a fleet adapter loads for each revision, the
    robots' interface unchanged, and what :func:`tmpnav.export.move_files.read_team` reads back."""
    from tmpnav.export.nav2 import files
    from tmpnav.report.plan_json import plan_document

    tag = "" if report.revision is None else f".rev{report.revision.number}"
    return files(plan_document(report), tag)


class Session:
    """A fleet manager's planning session: load once, plan, then update with the team's state as
    it goes and get the next plan. Each update revises the current plan (its state's ``time`` is
    counted from the current plan's start); the scenario and its world stay loaded, and the cost
    cache is the options' (a warm cache keeps replans short).

    ::

        session = Session("configs/building-4robots.yaml")
        first = session.plan()
        second = session.update(TeamState(Path("state"), time=95.5, doors={"door-B6": False}))
        files = nav2_files(second)        # r1.moves.rev1.yaml, ...
    """

    def __init__(self, scenario_path: str | Path, options: Options | None = None):
        from tmpnav import pipeline

        self.path = scenario_path
        self.options = options or pipeline.PlanOptions()
        self.loaded = pipeline.load_world(scenario_path, self.options.overrides)
        self.current: PlanReport | None = None

    def plan(self) -> PlanReport:
        """The first plan (revision 0)."""
        from tmpnav import pipeline

        self.current = pipeline.plan(self.path, self.options, loaded=self.loaded)
        return self.current

    def update(self, state: TeamState | str | Path) -> PlanReport:
        """The plan of the rest of the work from ``state`` (a TeamState, or a state file); it
        becomes the current plan."""
        from tmpnav.report.plan_json import plan_document

        if self.current is None:
            raise InputError("the session has no plan yet: call plan() first")
        team = state if isinstance(state, TeamState) else read_state(Path(state))
        doc = json.loads(json.dumps(plan_document(self.current)))  # plan.json as a fleet adapter reads it
        number = self.current.revision.number if self.current.revision is not None else 0
        self.current = _revised(self.path, self.loaded, Path(f"revision-{number}"), doc, team, self.options)
        return self.current
