"""``tmpnav replan``: the plan of the rest of the work, from where the team is (tmpnav/replan/)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from tmpnav.cli.commands import cli, warn_conflicts, warn_scenario, wrote_into
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

#: what decided a revision's plan (tmpnav.results.Revision.rule), as the command says it
RULES = {
    "search": "the search (its best plan)",
    "repair": "repair (the rest of the old plan, with the goals left over inserted where they cost least "
    "within their windows; the search found nothing better)",
}


@cli.command()
@SCENARIO_ARG
@click.option(
    "--plan",
    "plan_path",
    required=True,
    type=click.Path(path_type=Path, dir_okay=False, exists=True),
    help="The plan.json being executed (of tmpnav plan, or of an earlier tmpnav replan).",
)
@click.option(
    "--state",
    "state_path",
    required=True,
    type=click.Path(path_type=Path, dir_okay=False, exists=True),
    help="Where the team is (YAML or JSON): time, robots' poses and covariances, status down or a service "
    "interrupted, rooms visited, doors, goals (rooms or jobs) to add or remove (docs/replan.md).",
)
@output_option(
    True,
    "Directory for the revision's plan.json, plan.png, schedule.png, domain.pddl, problem.pddl (not the --plan's "
    "own folder).",
    default_text="write no files",
)
@option(
    "--export",
    "exports",
    multiple=True,
    type=click.Choice(["nav2"]),
    default_text="none",
    help="Also write the revision for ROS 2 navigation into DIR/nav2/ (needs -o DIR), as tmpnav plan --export "
    "nav2 does, each file name with the revision's number (r1.moves.rev1.yaml).",
)
@oracle_options
@report_errors
def replan(
    scenario: Path, plan_path: Path, state_path: Path, output: Path | None, exports: tuple[str, ...], **kw: Any
) -> None:
    """Plan the rest of the work from where the team is now.

    Reads the plan being executed and the team's state at TIME (docs/replan.md): each robot
    starts from its belief then, the goals done are left out, robots that are down leave the
    team (the others take their goals), a robot at its station finishes its service first,
    doors close or open, goals (rooms or jobs) are added or removed. The rest of the old plan,
    with the goals left over inserted where they cost least within their windows, is the
    search's first incumbent; move costs the change leaves valid come from the cache. Unless
    --search or --anytime-budget say otherwise, the anytime search plans it with a tenth of a
    first plan's budget, at least 1 s: the team is waiting. The revision's plan.json has the
    old schema, times from the revision's start, and its number and start time in
    ``revision``. Goals no robot can reach any more (a closed door, a window that closes
    before any robot can get there) are named one per line (exit code 12); the rest is
    planned and written.
    """
    from tmpnav.pipeline import pddl_texts, searches_over
    from tmpnav.replan import replan as run_replan
    from tmpnav.report.text import plan_summary

    if output is not None and output.resolve() == plan_path.resolve().parent:
        raise click.BadParameter(
            f"{output} holds the plan being revised ({plan_path.name}); expected another directory, so that the plan "
            "stays as it was",
            param_hint="'-o' / '--output'",
        )
    if exports and output is None:
        raise click.UsageError("--export needs -o DIR: the waypoint files go to DIR/nav2/")
    check_planner(scenario, kw["planner_name"])
    report = run_replan(scenario, plan_path, state_path, plan_options(kw))
    searches_over()  # ENHSP's JVM is not needed past here
    warn_scenario(report.scenario, bool(kw.get("no_range_sensor")))
    warn_conflicts(report)
    written: list[Path] = []
    if output is not None:
        from tmpnav.replan import nav2_files
        from tmpnav.report.outputs import write_outputs

        nav2 = {f"nav2/{name}": text for name, text in nav2_files(report).items()} if "nav2" in exports else {}
        with writing(output):
            written = write_outputs(report, output, pddl_texts(report), nav2)
    revision = report.revision
    assert revision is not None
    click.echo(
        f"revision {revision.number} of {Path(revision.previous).name}, from {revision.start_time:.1f} s: "
        f"{len(revision.done)} goal rooms done" + (f", down: {', '.join(revision.down)}" if revision.down else "")
    )
    if revision.held:
        click.echo(
            "finishing their services first: "
            + ", ".join(f"{robot} at {room} for {seconds:.1f} s" for robot, room, seconds in revision.held)
        )
    click.echo(f"decided by: {RULES[revision.rule]}")
    click.echo(plan_summary(report))
    if output is not None:
        click.echo(wrote_into(output, written))
    for room, why in revision.unreachable:
        click.echo(f"error: goal {room} is left out: {why}", err=True)
    if revision.unreachable:
        from tmpnav.errors import UNREACHABLE_GOALS

        sys.exit(UNREACHABLE_GOALS)
