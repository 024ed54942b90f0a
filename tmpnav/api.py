"""tmpnav from Python, without the command line.

    import tmpnav

    scenario = tmpnav.load("configs/corridor.yaml")          # validated, as `tmpnav validate`
    result = tmpnav.plan("configs/corridor.yaml", planner="enhsp-blind", timeout=60)
    print(result.status, result.planner_cost, result.resimulated_cost)
    print(result.makespan, result.objective, result.risk, result.conflicts, result.warnings)
    for step in result.steps:
        print(step.index, step.moves, step.resimulated_cost)
    result.save("out")                                       # plan.json, plan.png, schedule.png
    result.export_nav2("out/nav2")                           # waypoint files per robot

    proposal = tmpnav.segment_map("map.yaml", min_area=3.0)  # rooms, doors, landmark candidates
    tmpnav.write_skeleton(proposal, "scenario.yaml")

A path ``configs/NAME.yaml`` (or ``configs/office/office.yaml``) names a scenario or map shipped
with tmpnav when there is no such file under the working directory, as on the command line.

Errors are the library's typed exceptions (:mod:`tmpnav.errors`): ``ScenarioError`` lists every
problem of a scenario or map, ``PlannerError`` and its subclasses say how planning failed.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported lazily: `import tmpnav` stays fast
    from tmpnav.belief.conflicts import Conflict
    from tmpnav.export.nav2 import Waypoint
    from tmpnav.results import PlanReport
    from tmpnav.rooms.proposal import Proposal
    from tmpnav.types import Scenario, TrajectoryStep

__all__ = ["PlanResult", "Step", "export_nav2", "load", "plan", "segment_map", "write_skeleton"]


def load(path: str | Path) -> Scenario:
    """Load and check a scenario file: the format, then its geometry against the map (every
    problem at once in a :class:`~tmpnav.errors.ScenarioError`)."""
    from tmpnav.pipeline import load_world

    return load_world(_shipped_or(path))[0]


def _shipped_or(path: str | Path) -> Path:
    """``path``, or the shipped file ``configs/...`` names when there is no such file here."""
    from tmpnav.shipped import resolve

    return resolve(Path(path))


@dataclass(frozen=True)
class Step:
    """One step of the plan: one robot moving alone, or two moving together."""

    index: int  # 1-based, in execution order
    moves: tuple[tuple[str, str, str], ...]  # (robot, from, to) per robot of the step
    planner_cost: float  # as the task planner saw it (cost table)
    resimulated_cost: float  # with beliefs carried over from the previous steps
    goal_poses: tuple[tuple[float, float, float], ...]  # per robot: x, y (m), theta (rad)

    @property
    def robots(self) -> tuple[str, ...]:
        return tuple(m[0] for m in self.moves)


@dataclass(frozen=True, eq=False)
class PlanResult:
    """A plan and what comes with it. ``report`` is the pipeline's full report."""

    report: PlanReport

    @property
    def scenario(self) -> Scenario:
        return self.report.scenario

    @property
    def status(self) -> str:
        """``solved-optimally`` or ``solved-satisficing``."""
        return self.report.status.value

    @property
    def planner_cost(self) -> float:
        return float(self.report.planner_cost)

    @property
    def makespan(self) -> float:
        """When the last robot ends its last move (s, on the team's clock, re-simulated)."""
        return float(self.report.schedule.makespan)

    @property
    def objective(self) -> tuple[str, float, str]:
        """What the plan minimised, its value (re-simulated) and the value's units: for example
        ``("weighted", 531.6, "cost")`` or ``("makespan", 286.5, "s")``."""
        from tmpnav.report.schedule import objective_values

        o = objective_values(self.report)
        return o.name, float(o.own), o.units

    @property
    def risk(self) -> float:
        """The plan's collision bound: an upper bound on the probability that any robot touches a
        wall along the plan (docs/models.md, "Collision bound")."""
        return float(self.report.risk)

    @property
    def largest_move_risk(self) -> float:
        """The collision bound of the plan's riskiest move (what ``max_risk`` limits)."""
        return float(self.report.worst_risk)

    @property
    def largest_std(self) -> dict[str, float]:
        """Each robot's largest position std along the plan (m): along the widest axis of its
        position covariance, the square root of the largest eigenvalue (as plan.json's)."""
        return {robot: float(s) for robot, s in self.report.largest_std().items()}

    @property
    def conflicts(self) -> list[Conflict]:
        """Robots still in each other's way, by the independent checker (empty when none)."""
        from tmpnav.report.quality import plan_conflicts

        return plan_conflicts(self.report)

    @property
    def warnings(self) -> list[str]:
        """Each reason to doubt the plan, one message each, as the summary's ``warning:`` lines."""
        from tmpnav.report.quality import plan_warnings

        return [w.message for w in plan_warnings(self.report)]

    @property
    def resimulated_cost(self) -> float:
        return float(self.report.resimulated_cost)

    @property
    def steps(self) -> list[Step]:
        return [
            Step(
                index=int(a.index),
                moves=tuple((str(robot), str(origin), str(target)) for robot, origin, target in a.moves),
                planner_cost=float(a.planner_cost),
                resimulated_cost=float(a.resimulated_cost),
                goal_poses=tuple((float(x), float(y), float(theta)) for x, y, theta in a.goal_poses),
            )
            for a in self.report.actions
        ]

    @property
    def trajectories(self) -> dict[str, list[TrajectoryStep]]:
        """Each robot's re-simulated belief (mean, covariance) at every control step."""
        return dict(self.report.trajectories)

    def document(self) -> dict[str, Any]:
        """The plan as the plan.json document (docs/plan-json.md)."""
        from tmpnav.report.plan_json import plan_document

        return plan_document(self.report)

    def waypoints(self) -> dict[str, list[Waypoint]]:
        """Each robot's waypoints in the map frame, sync points of paired moves marked."""
        from tmpnav.export.nav2 import waypoints

        return waypoints(self.document())

    def save(self, directory: str | Path) -> list[Path]:
        """Write plan.json, plan.png and schedule.png into ``directory``; returns the paths."""
        from tmpnav.report.outputs import write_outputs

        return write_outputs(self.report, Path(directory), None)

    def export_nav2(self, directory: str | Path) -> list[Path]:
        """Write each robot's waypoint files for nav2 into ``directory``; returns the paths."""
        return export_nav2(self.document(), directory)


def plan(
    scenario: str | Path,
    *,
    encoding: str | None = None,
    planner: str | None = None,
    timeout: float | None = None,
    pair_min_gain: float | None = None,
    mutual_observations: bool | None = None,
    range_sensor: bool | None = None,
    search: str | None = None,
    time_budget: float | None = None,
    costs: str | None = None,
    objective: str | None = None,
    max_risk: float | str | None = None,
    keep_apart: bool | None = None,
    accept_risk: bool = False,
    cache_dir: str | Path | None = None,
    use_cache: bool = True,
    workers: int | None = None,
    executor: str = "processes",
) -> PlanResult:
    """Plan a scenario file, as ``tmpnav plan`` does; keyword arguments override the file's
    choices like the command's options of the same names (``max_risk="none"`` lifts the chance
    constraint, as ``--max-risk none`` does)."""
    from tmpnav.pipeline import NO_THRESHOLD, PlanOptions
    from tmpnav.pipeline import plan as run

    _check_choices(
        search=search,
        costs=costs,
        objective=objective,
        timeout=timeout,
        time_budget=time_budget,
        pair_min_gain=pair_min_gain,
        max_risk=None if max_risk == "none" else max_risk,
    )
    options = PlanOptions.of(
        encoding=encoding,
        planner=planner,
        timeout=timeout,
        pair_min_gain=pair_min_gain,
        mutual_observations=mutual_observations,
        range_sensor=range_sensor,
        search=search,
        time_budget=time_budget,
        costs=costs,
        objective=objective,
        max_risk=NO_THRESHOLD if max_risk == "none" else max_risk,
        keep_apart=keep_apart,
        accept_risk=accept_risk,
        cache_dir=Path(cache_dir) if cache_dir is not None else None,
        use_cache=use_cache,
        workers=workers,
        executor=executor,
    )
    return PlanResult(run(_shipped_or(scenario), options))


def _check_choices(**values: object) -> None:
    """The keyword arguments of :func:`plan`, checked as the command line checks its options."""
    from tmpnav.choices import COSTS, OBJECTIVES, SEARCHES
    from tmpnav.errors import InputError

    choices: dict[str, tuple[str, ...]] = {"search": SEARCHES, "costs": COSTS, "objective": OBJECTIVES}
    for name, value in values.items():
        if value is None:
            continue
        if name in choices and value not in choices[name]:
            raise InputError(f"plan(): {name}={value!r} is not one of {', '.join(choices[name])}")
        if name not in choices:
            number = value if isinstance(value, int | float) else math.nan
            low_ok = number >= 0 if name == "pair_min_gain" else number > 0
            in_range = name not in ("pair_min_gain", "max_risk") or number <= 1
            if not (math.isfinite(number) and low_ok and in_range):
                raise InputError(f"plan(): {name}={value!r} is not a finite number in its range")


def export_nav2(plan_json: str | Path | dict[str, Any], directory: str | Path) -> list[Path]:
    """Write nav2 waypoint files for a plan: a plan.json file or its document (a dict)."""
    from tmpnav.export.nav2 import write_nav2

    doc = json.loads(Path(plan_json).read_text(encoding="utf-8")) if not isinstance(plan_json, dict) else plan_json
    return write_nav2(doc, Path(directory))


def segment_map(
    map_yaml: str | Path, *, min_area: float = 3.0, max_rooms: int | None = None, max_area: float = 100.0
) -> Proposal:
    """Rooms (and the places of halls larger than ``max_area`` m²), doors, landmark candidates,
    placeholder robots and goals for a ROS map, as ``tmpnav rooms`` finds them."""
    from tmpnav.rooms.proposal import propose, read_map
    from tmpnav.rooms.segment import SegmentParams

    spec, grid = read_map(_shipped_or(map_yaml))
    return propose(spec, grid, SegmentParams(min_area=min_area, max_area=max_area, max_rooms=max_rooms))


def write_skeleton(proposal: Proposal, path: str | Path) -> Path:
    """Write the scenario skeleton of ``proposal`` to ``path`` (the map referred to relative to it)."""
    from tmpnav.rooms.skeleton import save, skeleton

    target = Path(path)
    save(target, skeleton(proposal, target))
    return target
