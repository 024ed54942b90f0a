"""Replanning from where the team is (``tmpnav replan``, docs/replan.md): the state file
(:mod:`tmpnav.replan.state`), the revised scenario (:mod:`tmpnav.replan.revise`) and the run
that plans it, the rest of the old plan as the search's incumbent."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tmpnav.errors import InputError
from tmpnav.replan.revise import Revision, revise
from tmpnav.replan.state import TeamState, read_state
from tmpnav.results import PlanReport
from tmpnav.types import Scenario
from tmpnav.world import World

if TYPE_CHECKING:
    from tmpnav.pipeline import PlanOptions as Options

__all__ = ["Revision", "TeamState", "read_plan", "read_state", "replan"]


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
    scenario_path: str | Path, plan_path: str | Path, state: str | Path | TeamState, options: Options | None = None
) -> PlanReport:
    """The plan of the rest of the work, from the team's state: the scenario revised
    (:func:`tmpnav.replan.revise.revise`) and planned as ``tmpnav plan`` plans, the rest of the
    old plan as the anytime search's incumbent; the report carries the revision."""
    from tmpnav import pipeline
    from tmpnav.world.build import build

    options = options or pipeline.PlanOptions()
    team = state if isinstance(state, TeamState) else read_state(Path(state))
    doc = read_plan(Path(plan_path))
    scenario, world = pipeline.load_world(scenario_path, options.overrides)

    def world_of(revised: Scenario | None) -> World:
        return world if revised is None else build(revised)

    revised, new_world, revision = revise(scenario, world_of, Path(plan_path), doc, team)
    report = pipeline.plan(scenario_path, options.but(incumbent=revision.incumbent), loaded=(revised, new_world))
    return replace(report, revision=revision)
