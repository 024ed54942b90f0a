"""schedule.png: the plan's schedule as a Gantt chart -- who moves when, who waits, which moves are paired.

One row per robot (the scenario's order, top to bottom, each in its colour of plan.png), time
on the x axis in seconds from the plan's start, on the team's shared clock (all robots move at
once, :class:`~tmpnav.results.Schedule`):

- each move a bar from its start to its end, labelled with the room it goes to (inside the bar
  when it fits, else just above or below it) and, where there is room, its plan step (``#k``,
  the step of the summary's table and of plan.png's badges);
- a wait (the robot is ready but its move starts later: its partner is not ready yet, or it is
  held back to keep clear of another robot) hatched, labelled ``wait`` (``wait for r2``) where
  wide enough;
- the two bars of a paired move outlined in black and joined at their common start by a
  connector: they start together and observe each other on the way;
- a job's service time (``goals.jobs``: the robot stands at the station after it arrives) a
  pale dotted bar after its move, labelled ``service`` where wide enough;
- the time after a robot's last move, until the makespan, lightly shaded (``idle``);
- the makespan as a dashed line (and the planner's, dotted, when its schedule ends elsewhere).

Each element is one small function over the axes, called from :func:`schedule_figure`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle

from tmpnav.report import figures as fg
from tmpnav.report.schedule import T_TOL, objective_values
from tmpnav.results import PlanReport, Schedule, TimedMove

BAR = 0.56  # height of a bar, rows one unit apart
WIDTH = 12.0  # in
ROW_HEIGHT = 0.62  # in per robot
LABEL_PT = 8.5  # font size of the room labels
CHAR = 0.62  # average width of a character, in font sizes (a safe estimate for DejaVu Sans)
IDLE_ALPHA = 0.13
TOP = 0.5  # rows' worth of room above the first robot, for the makespan's label
LEGEND_BELOW = 0.6  # in, from the bottom of the axes to the legend: clear of the time axis's label


@dataclass(frozen=True)
class Layout:
    """Where things go: each robot's row (y of its bar's centre) and the size of one second in points."""

    rows: dict[str, float]
    colors: dict[str, str]
    horizon: float  # s: the x axis ends here
    points_per_second: float

    def fits(self, text: str, seconds: float, size: float = LABEL_PT, pad: float = 6.0) -> bool:
        """Whether ``text`` at font ``size`` fits in a bar ``seconds`` long, with ``pad`` points to spare."""
        return len(text) * CHAR * size + pad <= seconds * self.points_per_second


def _layout(report: PlanReport, ax: Axes, horizon: float) -> Layout:
    """The rows of the scenario's robots, in its order, and the scale of the axes' time."""
    names = [r.name for r in report.scenario.robots]
    for robot in report.schedule.robots:  # a robot of the schedule the scenario does not list (never expected)
        if robot not in names:
            names.append(robot)
    fig = ax.get_figure(root=True)
    inches = (fig.get_size_inches()[0] if fig is not None else WIDTH) * ax.get_position().width
    return Layout(
        rows={name: float(k) for k, name in enumerate(names)},
        colors=fg.robot_colors(names),
        horizon=horizon,
        points_per_second=72.0 * inches / max(1.01 * horizon, 1e-9),  # the x axis starts at -0.01 horizon
    )


def _text_color(color: str) -> str:
    """Black or white, whichever reads better on ``color``."""
    r, g, b = to_rgb(color)
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.6 else "white"


def _draw_windows(ax: Axes, schedule: Schedule, lay: Layout, windows: dict[str, tuple[float, float]]) -> None:
    """A job's window (goals.jobs) under the bar of the move into its room: a bracket from its
    earliest to its latest arrival, and the wait at the station until it opens, hatched."""
    for robot, y in lay.rows.items():
        for move in schedule.timeline(robot):
            window = windows.get(move.target)
            if window is None:
                continue
            earliest, latest = window[0], min(window[1], lay.horizon)  # a window open past the axis: an arrow
            low = y - BAR / 2 - 0.09  # rows grow downwards: just above the bar
            dark = fg.darker(lay.colors[robot], 0.7)
            ax.plot([earliest, latest], [low, low], color=dark, lw=1.4, zorder=4, solid_capstyle="butt")
            ax.plot([earliest, earliest], [low - 0.06, low + 0.06], color=dark, lw=1.4, zorder=4)
            if window[1] <= lay.horizon:
                ax.plot([latest, latest], [low - 0.06, low + 0.06], color=dark, lw=1.4, zorder=4)
            else:
                ax.plot([latest], [low], marker=">", color=dark, markersize=5, zorder=4)
            ax.text(
                earliest,
                low - 0.04,
                f" {move.target} window ",
                ha="left",
                va="bottom",
                fontsize=LABEL_PT - 2,
                color=dark,
                bbox={"fc": "white", "ec": "none", "alpha": 0.85, "pad": 0.5},
                zorder=5,
            )
            if move.opens > T_TOL:
                ax.add_patch(
                    Rectangle(
                        (move.end, y - BAR / 2), move.opens, BAR, fc="white", ec=dark, lw=0.8, hatch="////", zorder=3
                    )
                )


def _draw_moves(ax: Axes, schedule: Schedule, lay: Layout) -> None:
    """Each move a bar in its robot's colour, labelled with its room; a paired move outlined in black."""
    for robot, y in lay.rows.items():
        outside = 0  # labels put outside so far on this row: they alternate above and below
        for move in schedule.timeline(robot):
            color = lay.colors[robot]
            length = move.end - move.start
            paired = move.partner is not None
            edge = "black" if paired else fg.darker(color)
            if length <= T_TOL:  # a move of no length (already there): a tick, so it still shows
                ax.plot([move.start] * 2, [y - BAR / 2, y + BAR / 2], color=edge, lw=2.0, zorder=4)
            else:
                ax.add_patch(
                    Rectangle(
                        (move.start, y - BAR / 2), length, BAR, fc=color, ec=edge, lw=1.6 if paired else 0.8, zorder=3
                    )
                )
            outside += _label_move(ax, move, y, lay, outside)
            if move.service > T_TOL:  # the job's time at the station: standing, after the arrival
                ax.add_patch(
                    Rectangle(
                        (move.end + move.opens, y - BAR / 2),
                        move.service,
                        BAR,
                        fc=(*to_rgb(color), 0.35),
                        ec=edge,
                        lw=0.8,
                        hatch="..",
                        zorder=3,
                    )
                )
                if lay.fits("service", move.service):
                    ax.text(
                        move.end + move.opens + move.service / 2,
                        y,
                        "service",
                        ha="center",
                        va="center",
                        fontsize=LABEL_PT - 1.5,
                        color=fg.darker(color, 0.8),
                        bbox={"fc": "white", "ec": "none", "alpha": 0.85, "pad": 1.0},
                        zorder=5,
                    )


def _label_move(ax: Axes, move: TimedMove, y: float, lay: Layout, outside: int) -> int:
    """The room a move goes to, in its bar (with the step ``#k`` where there is room) or, when
    the bar is too short, above or below it (alternately). Returns 1 if placed outside."""
    length, middle = move.end - move.start, (move.start + move.end) / 2
    color = lay.colors[move.robot]
    inside = [text for text in (f"#{move.step + 1} {move.target}", move.target) if lay.fits(text, length)]
    if inside:
        ax.text(
            middle,
            y,
            inside[0],
            ha="center",
            va="center",
            fontsize=LABEL_PT,
            color=_text_color(color),
            weight="bold",
            zorder=5,
        )
        return 0
    above = outside % 2 == 0  # the rows grow downwards: above is at a smaller y
    ax.text(
        middle,
        y - BAR / 2 - 0.02 if above else y + BAR / 2 + 0.02,
        move.target,
        ha="center",
        va="bottom" if above else "top",
        fontsize=LABEL_PT - 1.5,
        color=fg.darker(color, 0.8),
        zorder=5,
    )
    return 1


def _draw_waits(ax: Axes, schedule: Schedule, lay: Layout) -> None:
    """Each wait hatched between the robot's being ready and its move's start, labelled where wide enough."""
    ready = {(m.step, m.robot): m.ready for m in schedule.moves}
    for move in schedule.moves:
        if move.wait <= T_TOL:
            continue
        y, color = lay.rows[move.robot], lay.colors[move.robot]
        ax.add_patch(
            Rectangle(
                (move.ready, y - BAR / 2),
                move.wait,
                BAR,
                fc="white",
                ec=fg.darker(color),
                hatch="////",
                lw=0.8,
                zorder=2,
            )
        )
        partner_ready = ready.get((move.step, move.partner)) if move.partner is not None else None
        waits_for = partner_ready is not None and abs(partner_ready - move.start) <= T_TOL
        for text in ([f"wait for {move.partner}"] if waits_for else []) + ["wait"]:
            if lay.fits(text, move.wait, LABEL_PT - 0.5, pad=10.0):
                ax.text(
                    move.ready + move.wait / 2,
                    y,
                    text,
                    ha="center",
                    va="center",
                    fontsize=LABEL_PT - 0.5,
                    color=fg.darker(color, 0.7),
                    zorder=5,
                    bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none"},
                )
                break


def _draw_idle(ax: Axes, schedule: Schedule, lay: Layout) -> None:
    """After each robot's last move, until the makespan, a light band: the robot has finished."""
    makespan = schedule.makespan
    for robot, y in lay.rows.items():
        moves = schedule.timeline(robot)
        done = max((m.done for m in moves), default=0.0)
        if makespan - done <= T_TOL:
            continue
        color = lay.colors[robot]
        ax.add_patch(
            Rectangle((done, y - BAR / 2), makespan - done, BAR, fc=(*to_rgb(color), IDLE_ALPHA), ec="none", zorder=1)
        )
        text = "idle" if moves else "no moves: idle"
        if lay.fits(text, makespan - done, LABEL_PT - 0.5):
            ax.text(
                (done + makespan) / 2,
                y,
                text,
                ha="center",
                va="center",
                fontsize=LABEL_PT - 0.5,
                color=fg.darker(color, 0.7),
                style="italic",
                zorder=5,
            )


def _draw_pairs(ax: Axes, schedule: Schedule, lay: Layout) -> None:
    """The two bars of each paired move joined at their common start."""
    seen: set[int] = set()
    for move in schedule.moves:
        if move.partner is None or move.step in seen:
            continue
        seen.add(move.step)
        other = next((m for m in schedule.moves if m.step == move.step and m.robot == move.partner), None)
        if other is None:
            continue
        ys = sorted((lay.rows[move.robot], lay.rows[other.robot]))
        x = max(move.start, other.start)
        ax.plot([x, x], [ys[0] + BAR / 2, ys[1] - BAR / 2], color="black", lw=1.6, zorder=6, solid_capstyle="butt")
        ax.plot([x, x], [ys[0] + BAR / 2, ys[1] - BAR / 2], "o", ms=4.5, mfc="white", mec="black", mew=1.2, zorder=7)


def _draw_makespans(ax: Axes, report: PlanReport, lay: Layout) -> None:
    """The makespan (dashed) and, when its schedule ends elsewhere, the planner's (dotted), each
    labelled to the left of its line at the top, the planner's a line lower."""
    top = -0.5 - TOP + 0.05
    o = objective_values(report)
    marks = [(o.makespan, "--", f"makespan {o.makespan:.1f} s")]
    if o.planner_makespan is not None and abs(o.planner_makespan - o.makespan) > T_TOL:
        marks.append((o.planner_makespan, ":", f"planner's makespan {o.planner_makespan:.1f} s"))
    for k, (x, style, text) in enumerate(marks):
        ax.plot([x, x], [top, len(lay.rows) - 0.5], ls=style, color="#333333", lw=1.3, zorder=4.5)  # under labels
        ax.annotate(
            text,
            (x, top),
            xytext=(-4, -1 - 11 * k),
            textcoords="offset points",
            ha="right",
            va="top",
            fontsize=8.5,
            color="#333333",
            bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.85},
            zorder=9,
        )


def _legend(ax: Axes, report: PlanReport, lay: Layout) -> None:
    """What the marks mean, below the axes; the waits, pairs and idle time only when the plan has some."""
    schedule = report.schedule
    grey = "#9a9a9a"
    items: list[tuple[Patch | Line2D, str]] = [
        (Patch(fc=grey, ec="#555555"), "move: to the room named (#k: plan step k)")
    ]
    if any(m.wait > T_TOL or m.opens > T_TOL for m in schedule.moves):
        items.append((Patch(fc="white", ec="#555555", hatch="////"), "wait: for a partner, held back, or for a window"))
    if any(m.service > T_TOL for m in schedule.moves):
        items.append((Patch(fc=(*to_rgb(grey), 0.35), ec="#555555", hatch=".."), "service: at the station for its job"))
    if report.scenario.goals.windows and any(m.target in report.scenario.goals.windows for m in schedule.moves):
        items.append(
            (
                Line2D([], [], color="#555555", lw=1.4, marker="|", markersize=7),
                "window: when the job's robot may arrive (it waits for it to open)",
            )
        )
    if any(m.partner for m in schedule.moves):
        items.append(
            (
                Line2D([], [], color="black", lw=1.6, marker="o", mfc="white", mec="black"),
                "paired move: start together, observe each other",
            )
        )
    if any(schedule.makespan - max((m.done for m in schedule.timeline(r)), default=0.0) > T_TOL for r in lay.rows):
        items.append((Patch(fc=(*to_rgb(grey), 3 * IDLE_ALPHA), ec="none"), "idle: done until the makespan"))
    items.append((Line2D([], [], ls="--", color="#333333"), "makespan: when the last robot is done"))
    o = objective_values(report)
    if o.planner_makespan is not None and abs(o.planner_makespan - o.makespan) > T_TOL:
        items.append(
            (Line2D([], [], ls=":", color="#333333"), "the planner's makespan: of the schedule it planned with")
        )
    below = LEGEND_BELOW / (ROW_HEIGHT * (len(lay.rows) + TOP))  # in axes heights
    ax.legend(
        [h for h, _ in items],
        [t for _, t in items],
        loc="upper center",
        bbox_to_anchor=(0.5, -below),
        ncol=min(3, len(items)),
        fontsize=8.5,
        frameon=False,
    )


def _title(report: PlanReport) -> str:
    """The plan's size and makespan, then its objective with the numbers that make it up."""
    sc, o = report.scenario, objective_values(report)
    n = len(report.actions)
    pairs = sum(len(a.moves) == 2 for a in report.actions)
    paired = f", {pairs} paired" if pairs else ""
    cost = report.resimulated_cost
    if o.units == "s":
        value = f"the makespan, {o.own:.1f} s, then the sum of action costs, {cost:.3f}"
    elif o.span_weight:
        value = f"cost {cost:.3f} + {o.span_weight:g} per s x {o.makespan:.1f} s = {o.value:.3f}"
    else:
        value = f"the sum of action costs, {o.value:.3f}"
    return (
        f"{sc.name}: schedule of {n} plan step{'s' if n != 1 else ''}{paired}, all robots at once; "
        f"makespan {o.makespan:.1f} s\n"
        f"objective {o.name}: {value} (re-simulated; costs are unit-less)"
    )


def schedule_figure(report: PlanReport) -> Figure:
    """The schedule figure (Gantt chart) of a :class:`~tmpnav.results.PlanReport`.

    The axes fill the figure (rows of ``ROW_HEIGHT`` inches, so bars keep their size whatever
    the team's size); the title, the time axis and the legend around them are kept by the
    tight bounding box figures are saved with (:func:`tmpnav.report.figures.render`)."""
    schedule = report.schedule
    rows = max(len(report.scenario.robots), len(schedule.robots), 1)
    fig, ax = fg.subplots((WIDTH, ROW_HEIGHT * (rows + TOP)))
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=1.0)
    horizon = 1.03 * max(schedule.makespan, report.task.makespan or 0.0, report.scenario.models.dt)
    lay = _layout(report, ax, horizon)
    ax.set_xlim(-0.01 * horizon, horizon)  # a pair's connector at 0 clear of the edge
    ax.set_ylim(len(lay.rows) - 0.5, -0.5 - TOP)  # the first robot on top; above it, room for the makespan's label
    _draw_idle(ax, schedule, lay)
    _draw_waits(ax, schedule, lay)
    _draw_moves(ax, schedule, lay)
    _draw_windows(ax, schedule, lay, report.scenario.goals.windows)
    _draw_pairs(ax, schedule, lay)
    _draw_makespans(ax, report, lay)
    _axes(ax, lay)
    ax.set_title(_title(report), fontsize=10)
    _legend(ax, report, lay)
    return fig


def _axes(ax: Axes, lay: Layout) -> None:
    """Robot names in their colours down the side, seconds along the bottom, a light grid of time."""
    ax.set_yticks(list(lay.rows.values()), list(lay.rows))
    for label in ax.get_yticklabels():
        label.set_color(lay.colors[label.get_text()])
        label.set_fontweight("bold")
    ax.tick_params(axis="y", length=0)
    ax.set_xlabel("time since the plan's start [s] (one clock for the whole team)")
    ax.grid(axis="x", color="#dddddd", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)


def plot_schedule(report: PlanReport, path: Path) -> None:
    """Write the schedule figure to ``path``, atomically, in the format its suffix names."""
    fg.save(schedule_figure(report), path)
