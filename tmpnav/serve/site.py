"""A site held warm for the service: the scenario and its world loaded once, each plan and
revision planned by the real pipeline (:mod:`tmpnav.pipeline`, :mod:`tmpnav.replan`), one run
at a time.

    site = Site("configs/building-4robots.yaml", cache_dir=None)
    report = site.plan(goals=None, time_budget=20, watch=Watch())
    revised = site.revise(goals=None, plan_json=Path(".../rev-0000.json"), state={...}, watch=Watch())

The roadmap, the numba kernels and the cost cache stay warm between calls: the world is built
once, the roadmap of a plan being revised is kept by :mod:`tmpnav.replan`, and the costs are in
the cache directory.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from tmpnav.errors import Problem, ScenarioError, TmpnavError
from tmpnav.results import PlanReport
from tmpnav.types import Scenario
from tmpnav.world import World


class Cancelled(TmpnavError):
    """A search cancelled by its client (``DELETE /jobs/{id}``) or by the service's time limit."""

    exit_code = 130


@dataclass
class Watch:
    """How a run is watched: told of its progress, and stopped when ``cancel`` is set. The
    pipeline's reporters call :meth:`oracle` and :meth:`search`; a cancelled run raises
    :class:`Cancelled` from the next of them (the run's workers and ENHSP are ended by the
    pipeline's own cleanup, as after Ctrl-C)."""

    tell: Callable[[dict[str, Any]], None] = lambda event: None
    cancel: threading.Event = field(default_factory=threading.Event)
    why: str = "cancelled by the client"

    def check(self) -> None:
        if self.cancel.is_set():
            raise Cancelled(f"the search was {self.why}; nothing was written")

    def oracle(self, done: int, total: int) -> None:
        self.check()
        if done == total or done % max(1, total // 50) == 0:  # about 50 events for the costs, not thousands
            self.tell({"stage": "costs", "done": done, "total": total})

    def search(self, seconds: float, best: float, bound: float | None, what: str) -> None:
        self.check()
        self.tell(
            {
                "stage": "search",
                "seconds": round(seconds, 3),
                "best": _finite(best),
                "bound": _finite(bound),
                "what": what,
            }
        )


class Site:
    """A scenario and its world, loaded once; plans and revisions of it, one run at a time."""

    def __init__(self, scenario_path: str | Path, cache_dir: Path | None = None):
        from tmpnav import pipeline
        from tmpnav.shipped import resolve

        self.path = resolve(Path(scenario_path))
        self.options = pipeline.PlanOptions.of(cache_dir=cache_dir)
        self.scenario, self.world = pipeline.load_world(self.path, self.options.overrides)
        self.document: dict[str, Any] = yaml.safe_load(self.path.read_text(encoding="utf-8"))
        #: one planning run at a time: the oracle's workers use both cores, and the pipeline's
        #: warm state (roadmaps, kernels) is not shared between threads
        self.running = threading.Lock()
        self._goals: dict[str, tuple[Scenario, World]] = {}
        threading.Thread(target=self._warm, name="tmpnav-warm-site", daemon=True).start()

    def _warm(self) -> None:
        """The site's paths computed ahead (tmpnav.pipeline.warm_site), before the first request
        that needs them, which waits for this as for any run. A site whose warming fails plans
        all the same: each run computes what it needs."""
        from tmpnav import pipeline

        # only a head start: the run that needs the paths computes them if this failed
        with self.running, contextlib.suppress(Exception):
            pipeline.warm_site(self.scenario, self.world, self.options)

    def loaded(self, goals: dict[str, Any] | None) -> tuple[Scenario, World]:
        """The site's scenario with ``goals`` (the scenario file's ``goals`` section) in place of its
        own, checked as ``tmpnav validate`` checks a scenario; the world is the site's."""
        if goals is None:
            return self.scenario, self.world
        key = yaml.safe_dump(goals, sort_keys=True)
        if key not in self._goals:
            self._goals[key] = self._with_goals(goals)
            while len(self._goals) > 16:
                self._goals.pop(next(iter(self._goals)))
        return self._goals[key]

    def _with_goals(self, goals: dict[str, Any]) -> tuple[Scenario, World]:
        from tmpnav import pipeline
        from tmpnav import world as world_stage
        from tmpnav.scenario.load import load_partial

        doc = dict(self.document, goals=goals)
        ros = (doc.get("map") or {}).get("ros")
        if isinstance(ros, str):  # the map file is named relative to the scenario
            doc["map"] = dict(doc["map"], ros=str((self.path.parent / ros).resolve()))
        with tempfile.TemporaryDirectory(prefix="tmpnav-serve-") as folder:
            body = Path(folder) / self.path.name
            body.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
            scenario, problems = load_partial(body)
        if scenario is not None:
            scenario = pipeline.apply_options(scenario, self.options.overrides)
            scenario = replace(self.scenario, goals=scenario.goals, roadmap=scenario.roadmap)
            problems += world_stage.check(scenario, self.world)
        if problems or scenario is None:
            raise ScenarioError([_in_body(p) for p in problems])
        return scenario, self.world

    def plan(self, goals: dict[str, Any] | None, time_budget: float | None, watch: Watch) -> PlanReport:
        """A first plan of the site with ``goals`` (None: the scenario's own), as ``tmpnav plan``."""
        from tmpnav import pipeline

        loaded = self.loaded(goals)
        options = self._watched(watch, time_budget)
        with self.running:
            watch.check()
            return pipeline.plan(self.path, options, loaded=loaded)

    def revise(
        self, goals: dict[str, Any] | None, plan_json: Path, state: Any, time_budget: float | None, watch: Watch
    ) -> PlanReport:
        """The revision of the plan in ``plan_json`` from the team's ``state`` (the data of a
        ``tmpnav replan`` state file), as ``tmpnav replan`` plans it."""
        from tmpnav.replan import replan
        from tmpnav.replan.state import state_of

        team = state_of(Path("state"), state)  # one-line messages naming "state: key"
        loaded = self.loaded(goals)
        options = self._watched(watch, time_budget)
        with self.running:
            watch.check()
            return replan(self.path, plan_json, team, options, loaded=loaded)

    def _watched(self, watch: Watch, time_budget: float | None) -> Any:
        extra: dict[str, Any] = {} if time_budget is None else {"time_budget": time_budget}
        return self.options.but(progress=watch.oracle, search_progress=watch.search, **extra)


def _finite(value: float | None) -> float | None:
    """A number for JSON: None for none, or for one that is not finite (no plan yet)."""
    return None if value is None or not math.isfinite(value) else float(value)


def _in_body(problem: Problem) -> Problem:
    """A problem of the goals a request gave, named as the request body's (its line is the
    temporary file's, of no use to the client)."""
    return Problem("body", problem.path, problem.message)
