"""The ``tmpnav`` command line: the only place that prints and chooses exit codes."""

from __future__ import annotations

import functools
import os
import sys
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from tmpnav import __version__
from tmpnav.errors import EXIT_CODES, ScenarioError, TmpnavError

EPILOG = "Exit codes: " + "; ".join(f"{code} {meaning}" for code, meaning in EXIT_CODES.items())


def report_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn library exceptions into one line per problem on stderr and an exit code.

    A bug prints one line too; set TMPNAV_DEBUG=1 to see its traceback.
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except ScenarioError as err:
            for problem in err.problems:
                click.echo(f"error: {problem}", err=True)
            sys.exit(err.exit_code)
        except TmpnavError as err:
            click.echo(f"error: {err}", err=True)
            sys.exit(err.exit_code)
        except KeyboardInterrupt:
            click.echo("error: interrupted", err=True)
            sys.exit(130)
        except click.exceptions.Exit:
            raise
        except click.ClickException:
            raise
        except Exception as err:
            if os.environ.get("TMPNAV_DEBUG"):
                traceback.print_exc()
            click.echo(
                f"error: internal error: {type(err).__name__}: {err} (set TMPNAV_DEBUG=1 for the traceback)", err=True
            )
            sys.exit(1)

    return wrapper


SCENARIO_ARG = click.argument("scenario", type=click.Path(path_type=Path, dir_okay=False))


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
    """Check a scenario file and report every problem (exit code 2 if any)."""
    from tmpnav.pipeline import load_world

    sc, world = load_world(scenario)
    rows, cols = world.grid.shape
    click.echo(
        f"{scenario}: ok: {len(sc.rooms)} rooms, {len(sc.doors)} doors, {len(sc.landmarks)} landmarks, "
        f"{len(sc.robots)} robots, map {cols}x{rows} cells of {world.grid.resolution:g} m"
    )


@cli.command()
@SCENARIO_ARG
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path, dir_okay=False),
    default=Path("world.png"),
    show_default=True,
    help="PNG file to write.",
)
@report_errors
def show(scenario: Path, output: Path) -> None:
    """Draw the world: map, rooms, doors, landmarks, robots with 2-sigma start ellipses."""
    from tmpnav.pipeline import load_world
    from tmpnav.report.world_plot import plot_world

    sc, world = load_world(scenario)
    plot_world(sc, world, output)
    click.echo(f"wrote {output}")


@cli.command()
@SCENARIO_ARG
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path, dir_okay=False),
    default=Path("roadmap.png"),
    show_default=True,
    help="PNG file to write.",
)
@report_errors
def roadmap(scenario: Path, output: Path) -> None:
    """Build the probabilistic roadmap (OMPL PRM) and draw it over the map."""
    from tmpnav.pipeline import load_world
    from tmpnav.report.roadmap_plot import plot_roadmap
    from tmpnav.roadmap import build_roadmap

    sc, world = load_world(scenario)
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    plot_roadmap(sc, world, rm, output)
    click.echo(f"wrote {output}: {rm.n_nodes} nodes, {len(rm.edges)} edges")


@cli.command()
@report_errors
def reference() -> None:
    """Print the scenario format reference (every key, unit, default) as Markdown."""
    from tmpnav.scenario.reference import markdown

    click.echo(markdown(), nl=False)


def main() -> None:
    """Console entry point."""
    cli(prog_name="tmpnav")
