"""Planner names, checked before any work.

``validate`` reports an unknown ``planner.name`` as a problem of the scenario (exit 2);
``plan``, ``export-pddl`` and ``simulate`` refuse an unknown ``--planner`` or
``planner.name`` before the roadmap and the oracle run (exit 4, as the planner stage
would after them).
"""

from __future__ import annotations

from pathlib import Path

from tmpnav.errors import PlannerUnavailableError, Problem
from tmpnav.scenario import display_path, load_partial
from tmpnav.types import Scenario

#: up-enhsp's engines (a dependency of tmpnav): known without importing unified-planning,
#: which takes a second; any other name is looked up among the installed engines
UP_ENHSP_ENGINES = ("enhsp", "enhsp-opt", "enhsp-any")


def unknown_planner(name: str) -> str | None:
    """Why ``name`` names no planner unified-planning can run here, or None."""
    from tmpnav.task.solve import EXTRA_ENGINES, installed_planners

    if name in EXTRA_ENGINES or name in UP_ENHSP_ENGINES:
        return None
    names = installed_planners()
    if name in names:
        return None
    return f"unknown planner {name!r}; installed unified-planning planners: {', '.join(names)}"


def planner_problems(scenario: Scenario) -> list[Problem]:
    """The scenario's ``planner.name`` as a problem of the file when no planner has it."""
    why = unknown_planner(scenario.planner.name)
    if why is None:
        return []
    path = "planner.name"
    return [Problem(display_path(scenario.source), path, why, scenario.line_of(path))]


def check_planner(scenario: Path, override: str | None) -> None:
    """Raise PlannerUnavailableError (exit 4) when the planner a run would use, ``--planner``
    or the scenario's, is unknown. A scenario that cannot be read is left to the pipeline,
    which reports all its problems."""
    name = override
    if name is None:
        loaded, _ = load_partial(scenario)
        if loaded is None:
            return
        name = loaded.planner.name
    if why := unknown_planner(name):
        raise PlannerUnavailableError(why)
