"""``tmpnav simulate`` and ``tmpnav bench``: the paper's evaluation (Fig. 3), from the command line.

``simulate`` executes a plan with simulated noise (tmpnav/execution.py), ``bench`` times planning
runs against the number of rooms or robots (tmpnav/bench/). Registered on the group of
:mod:`tmpnav.cli.commands` when :mod:`tmpnav.cli` is imported.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from tmpnav.cli.commands import cli, warn_conflicts, warn_scenario
from tmpnav.cli.options import (
    SCENARIO_ARG,
    option,
    oracle_options,
    output_option,
    plan_options,
    report_errors,
    seconds_option,
    writing,
)
from tmpnav.cli.planners import check_planner

if TYPE_CHECKING:
    from tmpnav.execution.localisers import Localisation

#: tmpnav.execution.localisers.LOCALISERS' names (that module is imported only by the commands that run them)
LOCALISER_NAMES = ("ekf", "amcl")
#: tmpnav.execution.localisers.FOLLOWERS' names
FOLLOWER_NAMES = ("auto", "waypoint", "rpp")
#: tmpnav.execution.localisers.STEERING's names
STEERING_NAMES = ("auto", "local", "estimate")


def amcl_options(command: Any) -> Any:
    """--nav2-params and --site: nav2's AMCL and the site it localises on (simulate --localiser amcl, calibrate)."""
    command = option(
        "--site",
        "site_text",
        default="typical",
        show_default=True,
        metavar="SITE",
        help="With nav2's AMCL: how the site the lidar scans differs from the map: typical (unmapped clutter, "
        "walls a few cm off, passing people), none (the map exactly), or key=value overrides of typical, e.g. "
        "clutter=1,people=0 (docs/site.md).",
    )(command)
    return option(
        "--nav2-params",
        type=click.Path(path_type=Path, dir_okay=False),
        default=None,
        metavar="FILE",
        default_text="nav2's defaults",
        help="With nav2's AMCL: a nav2 params YAML whose amcl: section sets AMCL's parameters (your robots').",
    )(command)


@cli.command()
@SCENARIO_ARG
@option(
    "--sessions",
    type=click.IntRange(min=1),
    default=None,
    default_text="25; 5 with --events",
    help="Simulated executions of the plan, each with its own noise.",
)
@option("--seed", type=int, default=0, show_default=True, help="Seed of the simulated noise.")
@option(
    "--events",
    "events_path",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    default_text="the plan executed as planned",
    metavar="EVENTS",
    help="Close the loop: a YAML file of what happens while the team works (robots stopped, slowed or "
    "down, doors closed, goals added; docs/replan.md). The team replans at each change and when a robot "
    "runs late; each session is also executed blind and with a plan that knew the events.",
)
@option(
    "--server",
    default=None,
    metavar="URL",
    default_text="plan in this process",
    help="With --events: the closed loop's plan and revisions come from the tmpnav serve at URL, started on "
    "the same scenario (each session plans a shift there and posts the team's state at each replan; "
    "docs/serve.md).",
)
@option(
    "--token",
    envvar="TMPNAV_SERVE_TOKEN",
    default=None,
    default_text="none",
    help="The token of the tmpnav serve of --server, when it was started with one.",
)
@output_option(
    True,
    "Directory for errors.csv, sessions.csv, moves.csv, hits.csv, consistency.csv, errors.png, summary.md "
    "(with --events: loop.csv, replans.csv, loop.json, summary.md).",
    default_text="write no files",
)
@click.option(
    "--replan",
    is_flag=True,
    help="Run the task planner even if the cache remembers its plan for this exact problem.",
)
@option(
    "--localiser",
    type=click.Choice(LOCALISER_NAMES),
    default="ekf",
    show_default=True,
    help="Who localises the simulated robots: ekf, tmpnav's joint EKF with the planner's sensor models; "
    "amcl, nav2's AMCL on each robot from its odometry and the lidar's scans of --site (needs the "
    "optional extra tmpnav[amcl], GPL-3; docs/amcl.md).",
)
@option(
    "--follower",
    type=click.Choice(FOLLOWER_NAMES),
    default="auto",
    show_default=True,
    help="Who steers the simulated robots along their moves: waypoint, turning on the spot at each node "
    "of the path; rpp, nav2's Regulated Pure Pursuit with nav2's defaults, run 20 times a second as nav2's "
    "controller server runs it (turns while it drives, slows at bends, near walls and on approach; "
    "docs/rpp.md); auto, the plan's own controller (models.controller: "
    "rpp for rpp, waypoint for turn-then-drive).",
)
@option(
    "--steer",
    type=click.Choice(STEERING_NAMES),
    default="auto",
    show_default=True,
    help="What the simulated robots steer on: local, their estimate placed among the walls by their lidar's "
    "nearby returns, as nav2's costmaps place obstacles, with every command checked against what they see "
    "(docs/amcl.md); estimate, their localiser's estimate alone; "
    "auto, local with --localiser amcl and estimate with ekf.",
)
@option(
    "--recoveries/--no-recoveries",
    default=True,
    show_default=True,
    help="With --steer local: when a robot's controller finds no command that keeps clear of what it sees, "
    "or it makes no progress, it runs nav2's recovery behaviours (clear, spin, wait, back up; 6 retries, "
    "then the move is given up; docs/amcl.md). --no-recoveries: it stands until its move's step budget ends.",
)
@amcl_options
@oracle_options(mutual=False)
@report_errors
def simulate(
    scenario: Path, sessions: int | None, seed: int, events_path: Path | None, output: Path | None, **kw: Any
) -> None:
    """Simulate the plan, with and without mutual observations.

    Each session samples the true initial poses from the initial beliefs, free of the map;
    then every robot follows its own moves at once (each move as the plan drives it: nav2's
    Regulated Pure Pursuit, or a waypoint follower; steering on the estimate, noisy
    controls), a paired move
    starting when both robots are there and no move before its planned start, with noisy
    observations of landmarks and of other robots, and the joint EKF with mutual
    observations (config 1) and without (config 2), on the same random
    draws. Prints the worst-case position error per robot and its reduction, the
    makespan executed against the planned one, and the executions in which a true pose hit
    a wall or two robots touched, with 95% Clopper-Pearson intervals.

    With --events the loop is closed: the team replans from its beliefs at each event that
    changes the problem and when a robot is late, and the summary gives each mode's goals
    done, dropped and lost, executed makespan and cost, next to the plan run blind and to a
    plan made knowing the events.
    """
    from tmpnav.execution import error_summary, execute
    from tmpnav.pipeline import plan as run_plan
    from tmpnav.pipeline import searches_over

    check_planner(scenario, kw["planner_name"])
    localisation = _localisation(
        kw.pop("localiser"),
        kw.pop("nav2_params"),
        kw.pop("site_text"),
        kw.pop("follower"),
        kw.pop("steer"),
        kw.pop("recoveries"),
    )
    server, token = kw.pop("server"), kw.pop("token")
    if server is not None and events_path is None:
        raise click.BadParameter(
            "plans from a service are the closed loop's; expected --events EVENTS with it", param_hint="--server"
        )
    if events_path is not None:
        kw.update(server=server, token=token)
        _closed_loop(scenario, events_path, sessions or 5, seed, output, kw, localisation)
        return
    sessions = sessions or 25
    started = time.perf_counter()
    report = run_plan(scenario, plan_options(kw))
    searches_over()  # ENHSP's JVM is not needed past here
    warn_scenario(report.scenario, bool(kw.get("no_range_sensor")))
    warn_conflicts(report)
    limit = report.scenario.planner.time_limit  # --time-limit: the plan and its executions
    left = None if limit is None else limit - (time.perf_counter() - started)
    result = execute(report, sessions, seed, kw["workers"], localisation, left)
    ran = len(next(iter(result.errors.values()), ()))
    lines = error_summary(result, ran)
    if ran < sessions:
        lines.insert(0, f"--time-limit {limit:g} s: {ran} of {sessions} sessions ran")
        sessions = ran
    if output is not None:
        from tmpnav.report.outputs import write_execution_outputs

        with writing(output):
            written = write_execution_outputs(report, result, sessions, output)
        lines += [f"wrote {path}" for path in written]
    click.echo("\n".join(lines))


def _localisation(
    kind: str,
    nav2_params: Path | None,
    site_text: str,
    follower: str = "auto",
    steer: str = "auto",
    recoveries: bool = True,
) -> Localisation:
    """The simulation's localiser, follower and steering from the command line: AMCL's parameters
    read and the site parsed only for ``amcl`` (one error line for a bad file or value)."""
    from tmpnav.execution.localisers import Localisation

    if kind != "amcl":
        return Localisation(kind, follower=follower, steer=steer, recoveries=recoveries)
    from tmpnav.execution.site import SiteNoise
    from tmpnav.scenario.nav2_params import AmclParams, read_nav2_params

    params = read_nav2_params(nav2_params) if nav2_params is not None else AmclParams()
    try:
        site = SiteNoise.parse(site_text)
    except ValueError as e:
        raise click.BadParameter(str(e), param_hint="--site") from None
    return Localisation(kind, params, site, follower, steer=steer, recoveries=recoveries)


def _closed_loop(
    scenario: Path,
    events_path: Path,
    sessions: int,
    seed: int,
    output: Path | None,
    kw: Any,
    localisation: Localisation | None = None,
) -> None:
    """``tmpnav simulate --events``: the closed loop (tmpnav.replan.loop)."""
    import json

    from tmpnav.pipeline import load_world
    from tmpnav.replan.events import read_events
    from tmpnav.replan.loop import closed_loop
    from tmpnav.replan.loop_report import document, replans_csv, runs_csv, summary

    server, token = kw.pop("server", None), kw.pop("token", None)
    options = plan_options(kw)
    loaded, _ = load_world(scenario, options.overrides)
    events = read_events(events_path, loaded)
    quiet = kw.get("quiet", False)
    say = None if quiet else lambda m: click.echo(m, err=True)
    result = closed_loop(scenario, events, sessions, seed, options, say, localisation, server, token)
    lines = summary(result)
    if output is not None:
        from tmpnav.atomic import write_files

        contents = {
            "loop.csv": runs_csv(result),
            "replans.csv": replans_csv(result),
            "loop.json": json.dumps(document(result), indent=1) + "\n",
            "summary.md": "\n".join(lines) + "\n",
        }
        with writing(output):
            written = write_files(output, contents)
        lines += [f"wrote {path}" for path in written]
    click.echo("\n".join(lines))


@cli.command(short_help="Time planning runs against the number of rooms or of robots.")
@option(
    "--rooms",
    "rooms_text",
    default="2..10:2",
    show_default=True,
    help="Rooms to visit per run: A..B is every count from A to B, A..B:S every S-th (2..10:2 is the "
    "paper's 2, 4, ..., 10), or a list A,B,C.",
)
@option(
    "--robots",
    "robots_text",
    default="2",
    show_default=True,
    help="Robots per run: a count, a range or a list as for --rooms; several make a robots experiment.",
)
@option(
    "--sessions",
    type=click.IntRange(min=1),
    default=25,
    show_default=True,
    help="Sessions (random goal draws) per point.",
)
@option(
    "--encoding",
    "encodings",
    multiple=True,
    metavar="ENCODING[:COSTS[:SEARCH]]",
    default_text="mixed",
    help="Variants to compare on the same draws (repeat the option): an encoding, optionally with "
    "--costs and --search values, e.g. mixed, paper, mixed:table, mixed:table:anytime.",
)
@seconds_option(
    "--anytime-budget",
    "time_budget",
    old=("--time-budget",),
    default_text="the scenario's planner.time_budget",
    help="A time cap on the anytime search in every run (its budget is work: the scenario's planner.work_budget).",
)
@option("--seed", type=int, default=0, show_default=True, help="Seed of the goal draws.")
@seconds_option(
    "--run-timeout",
    "timeout",
    old=("--timeout",),
    default=300.0,
    show_default=True,
    help="Seconds a run may take; then it is stopped and recorded as a timeout.",
)
@option(
    "--scenario",
    type=click.Path(path_type=Path, dir_okay=False),
    default_text="the shipped configs/corridor-{robots}robots.yaml",
    help="World to use; {robots} in it becomes the number of robots.",
)
@option(
    "--workers",
    type=click.IntRange(min=1),
    metavar="N",
    default_text="one per core",
    help="Worker processes per run that compute the costs of moves.",
)
@output_option(True, "Directory for bench.csv, bench.png, summary.md.", default=Path("bench-out"), show_default=True)
@click.option("-q", "--quiet", is_flag=True, help="No progress lines on stderr.")
@click.option(
    "--replot",
    is_flag=True,
    help="Run nothing: rewrite summary.md and bench.png from the bench.csv in -o DIR (give the run's --run-timeout).",
)
@report_errors
def bench(
    rooms_text: str,
    robots_text: str,
    sessions: int,
    encodings: tuple[str, ...],
    time_budget: float | None,
    seed: int,
    timeout: float,
    scenario: Path | None,
    workers: int | None,
    output: Path,
    quiet: bool,
    replot: bool,
) -> None:
    """Planning time against the number of rooms (paper, Fig. 3(b)) or of robots (Fig. 3(c)).

    Every run plans in its own process: cold (empty cache), warm (cost table and task
    plan from the cache) and replan (cost table from the cache, the task planner runs
    again); runs longer than --run-timeout are recorded as timeouts. Writes bench.csv,
    bench.png and summary.md.
    """
    from tmpnav.bench import experiment

    written: list[Path] = []
    if replot:
        run = experiment.replot(output / experiment.BENCH_CSV)
    else:
        spec = experiment.BenchSpec.parse(
            rooms_text, robots_text, sessions, list(encodings), seed, timeout, scenario, workers, time_budget
        )
        run = experiment.run(spec, None if quiet else (lambda line: click.echo(line, err=True)))
        with writing(output):
            written.append(experiment.write_csv(run, output))
    with writing(output):
        text, figures = experiment.write_summary(run, output, timeout)
    click.echo(text)
    for path in [*written, *figures]:
        click.echo(f"wrote {path}")


@cli.command(short_help="Fit the planner's lidar model to nav2's AMCL on a scenario.")
@SCENARIO_ARG
@amcl_options
@option(
    "--sessions",
    type=click.IntRange(min=1),
    default=4,
    show_default=True,
    help="Executions of the plan with AMCL per round.",
)
@option("--rounds", type=click.IntRange(min=1, max=20), default=4, show_default=True, help="Rounds of the fit at most.")
@option("--seed", type=int, default=0, show_default=True, help="Seed of the simulated noise.")
@option(
    "--workers",
    type=click.IntRange(min=1),
    metavar="N",
    default_text="one per core",
    help="Worker processes that run the executions.",
)
@output_option(
    False, "File for the fitted model (YAML: the localiser: line and the rounds as comments).", required=True
)
@click.option("-q", "--quiet", is_flag=True, help="No progress lines on stderr.")
@report_errors
def calibrate(
    scenario: Path,
    nav2_params: Path | None,
    site_text: str,
    sessions: int,
    rounds: int,
    seed: int,
    workers: int | None,
    output: Path,
    quiet: bool,
) -> None:
    """Fit the planner's scan model to what nav2's AMCL achieves on SCENARIO.

    Plans the scenario, executes the plan with nav2's AMCL localising every robot (the
    optional extra tmpnav[amcl]) on a site that differs from the map, and fits the model's
    information share so that the driving steps' actual errors against the plan's predicted
    covariance have a median NEES of 1-4 with at most 5% beyond 3 sigma (the middle of the
    shares that meet both); where no share can, so that 96% lie within 3 sigma. It plans
    again with each new share, up to --rounds times, and stops at a round that meets both. The same
    executions count the wall hits per metre driven: the scenario's failure_rate stays where
    the count agrees with it, else it becomes the count's upper 95% limit. The scenario's floor
    (floor_beams), heading spread (heading_blur) and prediction noise (prediction_noise) stay as
    they are. Writes the model as the line to put under models.range_sensor (docs/models.md,
    "What a localiser achieves", "Localisation failures")."""
    from tmpnav.atomic import write_files
    from tmpnav.execution.calibrate import calibrate as fit

    localisation = _localisation("amcl", nav2_params, site_text)
    say = None if quiet else (lambda m: click.echo(m, err=True))
    result = fit(scenario, localisation, sessions, rounds, seed, workers, say)
    text = result.yaml(str(scenario))
    with writing(output):
        write_files(output.parent, {output.name: text})
    click.echo(text.rstrip("\n"))
    click.echo(f"wrote {output}")
