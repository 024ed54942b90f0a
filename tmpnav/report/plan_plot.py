"""plan.png: the task-motion plan drawn as in the paper's Fig. 2.

The map with rooms, doors and landmarks; each robot's re-simulated belief mean in its colour
with 2-sigma ellipses of the (x, y) covariance along it, in the same colour; the rooms' pose
instantiations as small black dots; the start poses; a numbered badge at every plan step's
goal with the time the robot gets there on the team's shared clock (the schedule's: all robots
move at once); the costs (unit-less) and the makespan in the title. Each element is one small
function over the axes, so that another (risk markers) is one more function called from
:func:`plan_figure`; the schedule itself has its own figure (:mod:`tmpnav.report.schedule_plot`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.collections import PatchCollection
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Ellipse
from numpy.typing import NDArray

from tmpnav.cachedir import CacheDir
from tmpnav.numbers import probability
from tmpnav.report import figures as fg
from tmpnav.report.labels import keep_labels_inside
from tmpnav.results import PlanReport
from tmpnav.types import TrajectoryStep

N_SIGMA = 2.0
MAX_ELLIPSES = 45  # per robot: more and they merge into a band
WIDE = 0.45  # height / width of the view under which the figure is wider and the legend goes below
PLAN_LOCALISABILITY_POINTS = 8000  # the faint localisability map behind the plan: a coarse one is enough
#: offsets (points) of a badge that would hide another badge or a start marker; robot names sit up-right
NUDGES = ((-20.0, 10.0), (20.0, -14.0), (-20.0, -14.0), (0.0, 24.0))


def ellipse_spacing(report: PlanReport) -> float:
    """Distance (m) travelled by the belief mean between two drawn ellipses.

    Chosen so that the longest trajectory gets at most ``MAX_ELLIPSES`` ellipses, and never
    closer than 0.6 m, where neighbouring 2-sigma ellipses of a well-localized robot start to touch.
    """
    longest = max((_travelled(steps)[-1] for steps in report.trajectories.values() if steps), default=0.0)
    return max(0.6, longest / MAX_ELLIPSES)


def _travelled(steps: list[TrajectoryStep]) -> NDArray[np.float64]:
    """Cumulative distance (m) of the belief mean at every step."""
    xy = np.array([s.mean[:2] for s in steps], dtype=float).reshape(-1, 2)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(xy, axis=0), axis=1))])


def ellipse_steps(steps: list[TrajectoryStep], spacing: float, keep: set[int] | None = None) -> list[int]:
    """Indices of the steps to draw an ellipse at: one every ``spacing`` metres, the last step,
    and the steps in ``keep`` (the goals of the plan steps). Turning on the spot adds none."""
    if not steps:
        return []
    s = _travelled(steps)
    chosen, last = [0], 0.0
    for i in range(1, len(steps)):
        if s[i] - last >= spacing:
            chosen.append(i)
            last = s[i]
    chosen.append(len(steps) - 1)
    return sorted(set(chosen) | (keep or set()))


def goal_steps(report: PlanReport, robot: str) -> set[int]:
    """Indices of ``robot``'s trajectory steps at the goal node of each of its plan steps."""
    steps = report.trajectories.get(robot, [])
    found, i = set(), 0
    for action in report.actions:
        for move, path in zip(action.moves, action.paths, strict=True):
            if move[0] != robot:
                continue
            for node in path[1:]:
                i = next((j for j in range(i + 1, len(steps)) if steps[j].node == node), i)
            found.add(i)
    return found


def _draw_beliefs(ax: Axes, report: PlanReport, spacing: float) -> None:
    """Each robot's belief mean, and its 2-sigma ellipses in its own colour: filled lightly, outlined
    darker, so that two robots' ellipses in one corridor can be told apart."""
    colors = fg.robot_colors([r.name for r in report.scenario.robots])
    for index, (robot, color) in enumerate(colors.items()):
        steps = report.trajectories.get(robot, [])
        if not steps:
            continue
        xy = np.array([s.mean[:2] for s in steps], dtype=float)
        # later robots are drawn thinner on top, so robots that share a corridor both stay visible;
        # a fleet's robots that share a colour differ in their line
        line = fg.robot_line(index)
        ax.plot(xy[:, 0], xy[:, 1], color=color, ls=line, lw=_line_width(index), zorder=5 + 0.01 * index)
        patches = [
            fg.covariance_ellipse(np.array(steps[i].mean), np.array(steps[i].cov), N_SIGMA)
            for i in ellipse_steps(steps, spacing, goal_steps(report, robot))
        ]
        # one collection per robot: drawn as the patches would be, without a patch's own bookkeeping
        # (add_patch updates the data limits one patch at a time: a fifth of a replan's figure)
        ellipses = PatchCollection(
            patches,
            facecolor=(*to_rgb(color), 0.25),
            edgecolor=fg.darker(color),
            linewidth=0.9,
            linestyle=line,
            zorder=5.5,
        )  # above the lines: the small ellipses of a well-localized robot stay visible
        ax.add_collection(ellipses)


def _line_width(index: int) -> float:
    return max(1.1, 2.4 - 0.9 * index)


def plan_extent(
    report: PlanReport, margin: float = 1.0, min_aspect: float = 1.6
) -> tuple[float, float, float, float] | None:
    """The part of the map the plan uses (xmin, ymin, xmax, ymax): trajectories with their ellipses,
    start poses and the rooms moved from and to, plus ``margin`` metres, widened to at least ``min_aspect``
    (a tall strip beside the legend reads badly); None when that is most of the map."""
    xs: list[float] = []
    ys: list[float] = []
    for steps in report.trajectories.values():
        for st in steps:
            r = N_SIGMA * float(np.sqrt(max(st.cov[0][0], st.cov[1][1], 0.0)))
            xs += [st.mean[0] - r, st.mean[0] + r]
            ys += [st.mean[1] - r, st.mean[1] + r]
    rooms = {name for a in report.actions for m in a.moves for name in m[1:]}
    for room in report.scenario.rooms:
        if room.name in rooms:
            xs += [p[0] for p in room.polygon]
            ys += [p[1] for p in room.polygon]
    for robot in report.scenario.robots:
        xs.append(robot.pose.x)
        ys.append(robot.pose.y)
    mxmin, mymin, mxmax, mymax = report.world.grid.extent
    if not xs:
        return None
    box = (
        max(mxmin, min(xs) - margin),
        max(mymin, min(ys) - margin),
        min(mxmax, max(xs) + margin),
        min(mymax, max(ys) + margin),
    )
    box = _widen(box, (mxmin, mymin, mxmax, mymax), min_aspect)
    share = (box[2] - box[0]) * (box[3] - box[1]) / max((mxmax - mxmin) * (mymax - mymin), 1e-9)
    return None if share > 0.7 else box


def _widen(
    box: tuple[float, float, float, float], bounds: tuple[float, float, float, float], min_aspect: float
) -> tuple[float, float, float, float]:
    """``box`` grown sideways, inside ``bounds``, to at least ``min_aspect`` (width / height)."""
    xmin, ymin, xmax, ymax = box
    missing = min_aspect * (ymax - ymin) - (xmax - xmin)
    if missing <= 0:
        return box
    left = min(missing / 2, xmin - bounds[0])
    right = min(missing - left, bounds[2] - xmax)
    left = min(missing - right, xmin - bounds[0])
    return xmin - left, ymin, xmax + right, ymax


@dataclass(frozen=True)
class Arrival:
    """A robot at the goal of one of its plan steps: where, and when (s from the plan's start)."""

    step: int  # the plan step's index (1-based)
    robot: str
    xy: tuple[float, float]
    t: float | None  # None when the trajectory does not pass the goal node (should not happen)
    risk: float | None = None  # the move's collision bound


def arrivals(report: PlanReport) -> list[Arrival]:
    """Every robot's arrival at each of its plan steps' goals, in plan order, at the time its
    move ends on the shared clock (the schedule's)."""
    ends = {(m.step, m.robot): m.end for m in report.schedule.moves}
    return [
        Arrival(action.index, move[0], (float(pose[0]), float(pose[1])), ends.get((action.index - 1, move[0])), risk)
        for action in report.actions
        for move, pose, risk in zip(
            action.moves, action.goal_poses, action.risk or (None,) * len(action.moves), strict=True
        )
    ]


def _draw_step_badges(ax: Axes, report: PlanReport) -> None:
    """Numbered badges at every plan step's goal with the robot's arrival time beside, nudged apart
    when two fall on the same spot."""
    colors = fg.robot_colors([r.name for r in report.scenario.robots])
    placed = [(r.pose.x, r.pose.y) for r in report.scenario.robots]  # keep the start markers readable
    for arrival in arrivals(report):
        x, y = arrival.xy
        crowded = sum(1 for px, py in placed if (px - x) ** 2 + (py - y) ** 2 < 0.8**2)
        offset = (0.0, 0.0) if not crowded else NUDGES[(crowded - 1) % len(NUDGES)]
        color = colors[arrival.robot]
        fg.step_badge(ax, (x, y), str(arrival.step), color, offset)
        note = [] if arrival.t is None else [f"{arrival.t:.1f} s"]
        if arrival.risk is not None:
            note.append(at_most(arrival.risk))
        if note:
            fg.badge_note(ax, (x, y), ", ".join(note), color, offset)
        placed.append((x, y))


def at_most(risk: float) -> str:
    """A move's collision bound beside its goal: ``p≤0.012``, ``p<1e-6`` (tmpnav.numbers.probability)."""
    text = probability(risk)
    return "p<" + text[2:] if text.startswith("< ") else "p≤" + text


def _legend(ax: Axes, report: PlanReport, spacing: float) -> None:
    handles, labels = [], []
    kinds = _kinds_in_view(ax, report)
    for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):  # landmarks, pose instantiations
        if label == "pose instantiations" or label in kinds:
            handles.append(handle)
            labels.append(label)
    extra: list[tuple[Artist, str]] = []
    colors = fg.robot_colors([r.name for r in report.scenario.robots])
    fleet = len(colors) > len(fg.ROBOT_COLORS)  # one entry a robot, the ellipses' once for all
    for index, (robot, color) in enumerate(colors.items()):
        if not report.trajectories.get(robot):
            continue
        line = Line2D([], [], color=color, ls=fg.robot_line(index), lw=_line_width(index))
        extra.append((line, robot if fleet else f"{robot}: belief mean"))
        if not fleet:
            extra.append(
                (
                    Ellipse((0, 0), 1, 0.6, fc=(*to_rgb(color), 0.25), ec=fg.darker(color), lw=0.9),
                    f"{robot}: {N_SIGMA:g}σ (x, y) covariance, every {spacing:.1f} m",
                )
            )
    if fleet:
        extra.append(
            (
                Ellipse((0, 0), 1, 0.6, fc=(0.5, 0.5, 0.5, 0.25), ec="#555555", lw=0.9),
                f"{N_SIGMA:g}σ (x, y) covariance, every {spacing:.1f} m, along each robot's belief mean",
            )
        )
    extra.append(
        (
            Line2D([], [], marker="o", ms=11, mfc="white", mec="black", ls="none"),
            "goal of plan step k, and when the robot gets there",
        )
    )
    extra.append((Line2D([], [], marker="o", ms=9, color="#777777", ls="none"), "start pose (2σ initial ellipse)"))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    # beside a wide, flat map the legend would be taller than the map: put it underneath
    below = (y1 - y0) / max(x1 - x0, 1e-9) < WIDE
    ax.legend(
        [h for h, _ in extra] + handles,
        [label for _, label in extra] + labels,
        loc="upper center" if below else "upper left",
        bbox_to_anchor=(0.5, -_below_label(ax)) if below else (1.0, 1.0),
        ncol=(8 if fleet else 4) if below else (2 if fleet else 1),
        fontsize=9,
        frameon=False,
    )


def _below_label(ax: Axes, inches: float = 0.55) -> float:
    """``inches`` below the axes, as a fraction of their height: clear of the x axis label."""
    fig = ax.get_figure(root=True)
    height = (fig.get_size_inches()[1] if fig is not None else 1.0) * ax.get_position().height
    return inches / max(height, 1e-9)


def _kinds_in_view(ax: Axes, report: PlanReport) -> set[str]:
    """Landmark kinds with at least one marker inside the axes (the view may be a part of the map)."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    return {lm.kind for lm in report.scenario.landmarks if x0 <= lm.position[0] <= x1 and y0 <= lm.position[1] <= y1}


def _title(report: PlanReport) -> str:
    sc = report.scenario
    status = report.status.value
    mutual = "with mutual observations" if sc.models.mutual_observations else "without mutual observations"
    sensor = sc.models.range_sensor
    if sensor is not None and not sensor.localiser.fuses_others:
        mutual = "localised by the lidar alone (AMCL)"
    n = len(report.actions)
    duration = f", makespan {report.schedule.makespan:.1f} s (all robots at once)" if n else ""
    return (
        f"{sc.name}: {n} plan step{'s' if n != 1 else ''}{duration}, {mutual}\n"
        f"cost (unit-less): planner {report.planner_cost:.3f}, "
        f"re-simulated {report.resimulated_cost:.3f} ({report.encoding} encoding, {report.planner}, {status}); "
        f"collision bound: plan {probability(report.risk)}, largest move {probability(report.worst_risk)} "
        "(p≤ at each goal)"
    )


def plan_figure(report: PlanReport, crop: bool = True) -> Figure:
    """The plan figure of a :class:`~tmpnav.results.PlanReport`.

    With ``crop`` the view shows the part of the map the plan uses (see :func:`plan_extent`),
    so the ellipses of a short plan in a large map stay visible.
    """
    sc, world = report.scenario, report.world
    extent = plan_extent(report) if crop else None
    xmin, ymin, xmax, ymax = extent if extent is not None else world.grid.extent
    width = 15.0 if (ymax - ymin) / max(xmax - xmin, 1e-9) < WIDE else 12.0
    fig, ax = fg.new_axes(world, width=width, extent=extent, max_height=9.0)
    fg.draw_map(ax, world)
    # where the range sensor pins the robots down, faintly (tmpnav show --localisability draws it in full)
    cache = CacheDir(report.cache.directory) if report.cache.enabled and report.cache.directory else None
    view = (xmin, ymin, xmax, ymax)
    fg.draw_localisability(ax, sc, world, view, alpha=0.4, points=PLAN_LOCALISABILITY_POINTS, cache=cache)
    fg.draw_rooms(ax, sc, extent)
    fg.draw_doors(ax, sc)
    fg.draw_instantiations(ax, report.roadmap, label="pose instantiations")
    fg.draw_landmarks(ax, sc)
    spacing = ellipse_spacing(report)
    _draw_beliefs(ax, report, spacing)
    for i in range(len(sc.robots)):
        fg.draw_robot_start(ax, sc, i)
    _draw_step_badges(ax, report)
    if extent is not None:
        ax.set_xlim(extent[0], extent[2])
        ax.set_ylim(extent[1], extent[3])
        for text in ax.texts:  # room names of rooms outside the view would stretch the figure
            text.set_clip_on(True)
    ax.set_title(_title(report), fontsize=10)
    _legend(ax, report, spacing)
    keep_labels_inside(ax)
    return fig


def plot_plan(report: PlanReport, path: Path, crop: bool = True) -> None:
    """Write the plan figure (PNG) to ``path``, atomically."""
    fg.save(plan_figure(report, crop), path)
