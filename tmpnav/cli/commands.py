"""The commands of ``tmpnav``: each parses its options, calls the library, prints the result."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from tmpnav.cli.options import (
    SCENARIO_ARG,
    option,
    oracle_options,
    output_option,
    plan_options,
    report_errors,
    writing,
)
from tmpnav.cli.planners import check_planner
from tmpnav.errors import EXIT_CODES
from tmpnav.numbers import length
from tmpnav.types import RosMap
from tmpnav.version import __version__

if TYPE_CHECKING:
    from tmpnav.results import PlanReport
    from tmpnav.types import Scenario
    from tmpnav.world import World

EPILOG = "Exit codes: " + "; ".join(f"{code} {meaning}" for code, meaning in EXIT_CODES.items())


@click.group(epilog=EPILOG, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="tmpnav")
def cli() -> None:
    """Multi-robot task-motion planning for navigation in belief space.

    tmpnav decides which robot visits which room, in which order and along which
    roadmap path, minimising motion and uncertainty cost (c = M_u c_u + M_G c_G +
    M_Sigma trace(Sigma)), with robots that localize better when they see each other.
    """


@cli.command()
@SCENARIO_ARG
@report_errors
def validate(scenario: Path) -> None:
    """Check a scenario file and report every problem.

    Each problem is one line (file:line: key.path: message); exit code 2 if there is any.
    """
    from tmpnav.cli.planners import planner_problems
    from tmpnav.errors import ScenarioError
    from tmpnav.pipeline import load_world
    from tmpnav.scenario import load_partial

    try:
        sc, world = load_world(scenario)
    except ScenarioError as err:
        partial, _ = load_partial(scenario)  # read again, only to add the planner's name to the list
        raise ScenarioError([*err.problems, *(planner_problems(partial) if partial else [])]) from None
    if problems := planner_problems(sc):
        raise ScenarioError(problems)
    rows, cols = world.grid.shape
    n = len(sc.stations)
    stations = "" if not n else f", {n} station{'s' * (n > 1)}"
    click.echo(
        f"{scenario}: ok: {len(sc.places)} rooms{stations}, {len(sc.doors)} doors, {len(sc.landmarks)} landmarks, "
        f"{len(sc.robots)} robots, map {cols}x{rows} cells of {world.grid.resolution:g} m"
        + (f", specks up to {sc.map.despeckle:g} m cleared" if isinstance(sc.map, RosMap) and sc.map.despeckle else "")
    )
    warn_scenario(sc, world=world)


def warn_scenario(scenario: Scenario, asked_without_sensor: bool = False, world: World | None = None) -> None:
    """The scenario's warnings (tmpnav.scenario.advice; with its ``world``, starts near the walls:
    tmpnav.world.checks.start_advice), one line each on stderr; none about the range sensor when
    the command line asked to plan without it (--no-range-sensor)."""
    from tmpnav.scenario.advice import warnings
    from tmpnav.world.checks import start_advice

    for line in [*warnings(scenario), *(start_advice(scenario, world) if world is not None else [])]:
        if not (asked_without_sensor and "models.range_sensor" in line):
            click.echo(f"warning: {line}", err=True)


def warn_conflicts(report: PlanReport) -> None:
    """One line on stderr when the plan leaves robots in each other's way (a plan without a
    chance constraint, taken with --accept-risk, or not kept apart): a run that exits 0 with
    such a plan says so where scripts look, not only in the summary."""
    from tmpnav.report.quality import plan_conflicts

    conflicts = plan_conflicts(report)
    if not conflicts:
        return
    first, planner = conflicts[0], report.scenario.planner
    more = f" (and {len(conflicts) - 1} more)" if len(conflicts) > 1 else ""
    if not planner.keep_apart:
        hint = "--keep-apart keeps robots apart"
    elif planner.max_risk is None:
        hint = "--max-risk keeps robots apart within a threshold"
    else:
        hint = "taken as it is with --accept-risk"
    click.echo(
        f"warning: the plan leaves robots in each other's way: {' and '.join(first.robots)} at {first.t_from:.1f} s, "
        f"{length(first.closest_distance)} apart where {length(first.required_separation)} are needed{more}; "
        f"{hint} (docs/planning.md)",
        err=True,
    )


@cli.command()
@SCENARIO_ARG
@output_option(
    False,
    "Picture to write; its suffix names the format (.png, .svg, .pdf, ...).",
    figure=True,
    default=Path("world.png"),
    show_default=True,
)
@click.option(
    "--localisability",
    is_flag=True,
    help="Shade the map by how well one scan of the robots' range sensor pins a robot down (the position "
    "std along its worst direction): long featureless corridors and open floor beyond the sensor's range stand out.",
)
@report_errors
def show(scenario: Path, output: Path, localisability: bool) -> None:
    """Draw the world: map, rooms, doors, landmarks, robots.

    Robots are drawn at their start pose with the 2-sigma ellipse of their start belief, landmarks
    with the range of the landmark sensor (a ROS map: only its known free space).
    """
    from tmpnav.errors import InputError
    from tmpnav.pipeline import load_world
    from tmpnav.report.world_plot import plot_world

    sc, world = load_world(scenario)
    if localisability and sc.models.range_sensor is None:
        raise InputError(
            f"--localisability: {scenario} has no models.range_sensor; expected a scenario whose robots carry one"
        )
    with writing(output):
        plot_world(sc, world, output, localisability)
    click.echo(f"wrote {output}")


@cli.command()
@SCENARIO_ARG
@output_option(
    False,
    "Picture to write; its suffix names the format (.png, .svg, .pdf, ...).",
    figure=True,
    default=Path("roadmap.png"),
    show_default=True,
)
@report_errors
def roadmap(scenario: Path, output: Path) -> None:
    """Build the roadmap (OMPL's PRM) and draw it over the map."""
    from tmpnav.pipeline import load_world
    from tmpnav.report.roadmap_plot import plot_roadmap
    from tmpnav.roadmap import build_roadmap

    sc, world = load_world(scenario)
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    with writing(output):
        plot_roadmap(sc, world, rm, output)
    click.echo(f"wrote {output}: {rm.n_nodes} nodes, {len(rm.edges)} edges")


@cli.command()
@SCENARIO_ARG
@output_option(
    True, "Directory for plan.json, plan.png, schedule.png, domain.pddl, problem.pddl.", default_text="write no files"
)
@option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json"]),
    default="text",
    show_default=True,
    help="What to print on stdout: text (a summary) or json (the plan.json document).",
)
@click.option(
    "--replan",
    is_flag=True,
    help="Run the task planner even if the cache remembers its plan for this exact problem.",
)
@option(
    "--export",
    "exports",
    multiple=True,
    type=click.Choice(["nav2"]),
    default_text="none",
    help="Also write the plan for ROS 2 navigation into DIR/nav2/ (needs -o DIR): per robot and move a nav2 "
    "NavigateThroughPoses goal with its times, the team's schedule, and each robot's waypoints.",
)
@oracle_options
@report_errors
def plan(scenario: Path, output: Path | None, fmt: str, exports: tuple[str, ...], **kw: Any) -> None:
    """Plan who visits which room, in which order, along which path.

    Prints the task-motion plan (per step: robots, from, to, cost), the total cost as
    the planner saw it and as re-simulated with carried-over beliefs, and the time per
    stage. With -o DIR it also writes plan.json, plan.png, schedule.png (who moves when)
    and the PDDL files used.

    A cost table and a task plan computed before for the same inputs come from the cache
    (--no-cache: compute everything; --replan: run the task planner again anyway).

    The anytime search's budget is work (--anytime-work), so the same plan on any machine.
    Time limits: --planner-timeout bounds one run of the task planner (past it, an error),
    --anytime-budget caps the anytime search and --time-limit the whole command (past them,
    the best plan so far).
    """
    from tmpnav.pipeline import pddl_texts, searches_over
    from tmpnav.pipeline import plan as run_plan
    from tmpnav.report.plan_json import dumps, plan_document
    from tmpnav.report.text import plan_summary

    if exports and output is None:
        raise click.UsageError("--export needs -o DIR: the waypoint files go to DIR/nav2/")
    check_planner(scenario, kw["planner_name"])
    report = run_plan(scenario, plan_options(kw))
    searches_over()  # ENHSP's JVM is not needed past here
    warn_scenario(report.scenario, bool(kw.get("no_range_sensor")), report.world)
    warn_conflicts(report)
    written: list[Path] = []
    if output is not None:
        from tmpnav.export.nav2 import files as nav2_files
        from tmpnav.report.outputs import write_outputs

        pddl = pddl_texts(report)
        nav2: dict[str, str] = {}  # the plan and its waypoints are one group: all written, or none
        if "nav2" in exports:
            nav2 = {f"nav2/{name}": text for name, text in nav2_files(plan_document(report)).items()}
        with writing(output):
            written = write_outputs(report, output, pddl, nav2)
    if fmt == "json":
        click.echo(dumps(plan_document(report)))
    else:
        click.echo(plan_summary(report))
        if output is not None:
            click.echo(wrote_into(output, written))


def wrote_into(folder: Path, written: list[Path]) -> str:
    """One line for the files written into ``folder``: ``wrote out/: plan.json, plan.png, ...``."""
    names = [str(Path(p).relative_to(folder)) if Path(p).is_relative_to(folder) else str(p) for p in written]
    return f"wrote {str(folder).rstrip('/')}/: {', '.join(names)}"


@cli.command("export-pddl")
@SCENARIO_ARG
@output_option(True, "Directory for domain.pddl and problem.pddl.", required=True)
@oracle_options
@report_errors
def export_pddl(scenario: Path, output: Path, **kw: Any) -> None:
    """Write the PDDL domain and problem, costs included, for ENHSP.

    The files ENHSP accepts by hand (java -jar enhsp.jar -o domain.pddl -f problem.pddl).
    """
    from tmpnav.pipeline import export_problem
    from tmpnav.task.export import pddl_texts, write_pddl

    check_planner(scenario, kw["planner_name"])
    encoded = export_problem(scenario, plan_options(kw))
    texts = pddl_texts(encoded)
    with writing(output):
        written = write_pddl(output, texts)
    for path in written:
        click.echo(f"wrote {path}")


def _one_line_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    click.echo(f"warning: {message}", err=True)


def main() -> None:
    """Console entry point: warnings and command-line mistakes become one line each, never
    a traceback (click's own usage errors included: ``error: ... (see 'tmpnav plan --help')``).

    Every run is guarded (tmpnav.lifetime): SIGTERM ends it as cleanly as Ctrl-C, and no process
    it started outlives it, however it ends.
    """
    import warnings

    from tmpnav.lifetime import Terminated, check_signals, end_as_terminated, guard

    warnings.showwarning = _one_line_warning
    try:
        guard()
        code = cli.main(prog_name="tmpnav", standalone_mode=False)
        check_signals()  # a Ctrl-C that some library swallowed still ends the run as interrupted
    except click.exceptions.NoArgsIsHelpError as err:  # a bare `tmpnav`: the help, as asked
        click.echo(err.format_message())
        sys.exit(0)
    except click.UsageError as err:
        hint = f" (see '{err.ctx.command_path} --help')" if err.ctx is not None else ""
        click.echo(f"error: {err.format_message()}{hint}", err=True)
        sys.exit(err.exit_code)
    except click.ClickException as err:
        click.echo(f"error: {err.format_message()}", err=True)
        sys.exit(err.exit_code)
    except (click.Abort, KeyboardInterrupt):  # KeyboardInterrupt: Ctrl-C before click ran
        click.echo("error: interrupted", err=True)
        sys.exit(130)
    except Terminated:
        click.echo("error: terminated (SIGTERM)", err=True)
        end_as_terminated()
    sys.exit(code if isinstance(code, int) else 0)
