"""The ``tmpnav`` command line: the only place that prints and chooses exit codes."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import click

from tmpnav import __version__
from tmpnav.errors import EXIT_CODES, OutputError, ScenarioError, TmpnavError

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


def unwritable(path: Path, directory: bool) -> str | None:
    """Why ``path`` (an output directory, or a file when not ``directory``) cannot be
    written, or None. Nothing is created: a run that fails later leaves no empty folder.
    (click.Path has already refused a file where a directory is expected, and the reverse.)"""
    folder = (path if directory and path.is_dir() else path.parent).absolute()
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        return f"{folder} is a file, so {path} cannot be created"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"{folder} is not writable"
    return None


def output_option(directory: bool, help_text: str, **kwargs: Any) -> Callable[..., Any]:
    """``-o/--output``, checked before any work is done (a directory, or a file)."""

    def check(ctx: click.Context, param: click.Parameter, value: Path | None) -> Path | None:
        if value is not None and (why := unwritable(value, directory)):
            raise click.BadParameter(why, ctx=ctx, param=param)
        return value

    kind = click.Path(path_type=Path, file_okay=not directory, dir_okay=directory)
    return click.option("-o", "--output", type=kind, callback=check, help=help_text, **kwargs)


@contextlib.contextmanager
def writing(output: Path) -> Iterator[None]:
    """Outputs that fail to write late (a full disk) are one line, not an internal error."""
    try:
        yield
    except OSError as err:
        target = err.filename or output
        raise OutputError(f"cannot write {target}: {err.strerror or err}") from None


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
@output_option(False, "PNG file to write.", default=Path("world.png"), show_default=True)
@report_errors
def show(scenario: Path, output: Path) -> None:
    """Draw the world: map, rooms, doors, landmarks, robots with 2-sigma start ellipses."""
    from tmpnav.pipeline import load_world
    from tmpnav.report.world_plot import plot_world

    sc, world = load_world(scenario)
    with writing(output):
        plot_world(sc, world, output)
    click.echo(f"wrote {output}")


@cli.command()
@SCENARIO_ARG
@output_option(False, "PNG file to write.", default=Path("roadmap.png"), show_default=True)
@report_errors
def roadmap(scenario: Path, output: Path) -> None:
    """Build the probabilistic roadmap (OMPL PRM) and draw it over the map."""
    from tmpnav.pipeline import load_world
    from tmpnav.report.roadmap_plot import plot_roadmap
    from tmpnav.roadmap import build_roadmap

    sc, world = load_world(scenario)
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    with writing(output):
        plot_roadmap(sc, world, rm, output)
    click.echo(f"wrote {output}: {rm.n_nodes} nodes, {len(rm.edges)} edges")


def oracle_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Options shared by every command that computes action costs."""
    options = [
        click.option(
            "--encoding",
            type=click.Choice(["paper", "single", "mixed"]),
            help="Task encoding (overrides planner.encoding).",
        ),
        click.option(
            "--planner",
            "planner_name",
            metavar="NAME",
            help="unified-planning engine (overrides planner.name), e.g. enhsp-blind (default), enhsp-opt, enhsp.",
        ),
        click.option(
            "--timeout", type=click.FloatRange(min=0, min_open=True), metavar="S", help="Planner time limit in seconds."
        ),
        click.option(
            "--pair-min-gain",
            type=click.FloatRange(0, 1),
            metavar="G",
            help="Mixed encoding: minimum relative saving of a paired move.",
        ),
        click.option(
            "--no-mutual-observations",
            is_flag=True,
            help="Ignore mutual observations between robots (the paper's config 2).",
        ),
        click.option(
            "--cache-dir",
            type=click.Path(path_type=Path, file_okay=False),
            help="Oracle and roadmap cache (default: $XDG_CACHE_HOME/tmpnav).",
        ),
        click.option("--no-cache", is_flag=True, help="Compute every cost afresh and store nothing."),
        click.option(
            "--workers", type=click.IntRange(min=1), help="Local worker processes for the oracle (default: all cores)."
        ),
        click.option(
            "--executor",
            type=click.Choice(["processes", "serial", "ray"]),
            default="processes",
            show_default=True,
            help="Where oracle evaluations run.",
        ),
        click.option(
            "--ray-address",
            metavar="ADDR",
            help="Ray cluster to join with --executor ray (default: start a local one).",
        ),
        click.option("-q", "--quiet", is_flag=True, help="No progress bar."),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def plan_options(kw: dict[str, Any]) -> Any:
    from tmpnav.pipeline import PlanOptions

    return PlanOptions(
        encoding=kw["encoding"],
        planner=kw["planner_name"],
        timeout=kw["timeout"],
        pair_min_gain=kw["pair_min_gain"],
        mutual_observations=False if kw["no_mutual_observations"] else None,
        cache_dir=kw["cache_dir"],
        use_cache=not kw["no_cache"],
        replan=kw.get("replan", False),
        executor=kw["executor"],
        workers=kw["workers"],
        ray_address=kw["ray_address"],
        progress=None if kw["quiet"] else progress_bar("oracle"),
    )


def progress_bar(label: str) -> Callable[[int, int], None] | None:
    """A one-line progress bar on stderr, only when stderr is a terminal."""
    if not sys.stderr.isatty():
        return None

    def show(done: int, total: int) -> None:
        width = 30
        filled = int(width * done / max(total, 1))
        sys.stderr.write(f"\r{label} [{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
        if done >= total:
            sys.stderr.write("\r" + " " * (width + len(label) + 20) + "\r")
        sys.stderr.flush()

    return show


@cli.command()
@SCENARIO_ARG
@output_option(True, "Directory for plan.json, plan.png, domain.pddl, problem.pddl.")
@click.option(
    "--format",
    "fmt",
    type=click.Choice(["text", "json"]),
    default="text",
    show_default=True,
    help="What to print on stdout.",
)
@click.option(
    "--replan",
    is_flag=True,
    help="Run the task planner even if the cache remembers its plan for this exact problem.",
)
@oracle_options
@report_errors
def plan(scenario: Path, output: Path | None, fmt: str, **kw: Any) -> None:
    """Plan: which robot visits which room, in which order, along which path.

    Prints the task-motion plan (per step: robots, from, to, cost), the total cost as
    the planner saw it and as re-simulated with carried-over beliefs, and the time per
    stage. With -o DIR it also writes plan.json, plan.png and the PDDL files used.

    A cost table and a task plan computed before for the same inputs come from the cache
    (--no-cache: compute everything; --replan: run the task planner again anyway).
    """
    from tmpnav.pipeline import plan as run_plan

    report = run_plan(scenario, plan_options(kw))
    from tmpnav.report.plan_json import dumps, plan_document
    from tmpnav.report.text import summary

    written: list[Path] = []
    if output is not None:
        from tmpnav.report.outputs import write_outputs

        pddl = report.pddl_texts()
        with writing(output):
            written = write_outputs(report, output, pddl)
    if fmt == "json":
        click.echo(dumps(plan_document(report)))
    else:
        click.echo(summary(report))
        for path in written:
            click.echo(f"wrote {path}")


@cli.command("export-pddl")
@SCENARIO_ARG
@output_option(True, "Directory for domain.pddl and problem.pddl.", required=True)
@oracle_options
@report_errors
def export_pddl(scenario: Path, output: Path, **kw: Any) -> None:
    """Write the PDDL domain and problem (with the computed costs) that ENHSP accepts."""
    from tmpnav.pipeline import encode_only
    from tmpnav.task.export import pddl_texts, write_pddl

    encoded = encode_only(scenario, plan_options(kw))
    texts = pddl_texts(encoded)
    with writing(output):
        written = write_pddl(output, texts)
    for path in written:
        click.echo(f"wrote {path}")


@cli.group()
def cache() -> None:
    """Inspect or clear the oracle's disk cache."""


@cache.command("info")
@click.option(
    "--cache-dir",
    type=click.Path(path_type=Path, file_okay=False),
    help="Cache directory (default: $XDG_CACHE_HOME/tmpnav).",
)
@report_errors
def cache_info(cache_dir: Path | None) -> None:
    """Where the cache is, how big, how many entries."""
    from tmpnav.oracle.cache import default_cache_dir, info

    facts = info(cache_dir or default_cache_dir())
    roadmaps = list((Path(facts["directory"]) / "roadmaps").glob("*.npz"))
    click.echo(f"directory: {facts['directory']}")
    if not facts["exists"]:
        click.echo("empty (no cache file yet)")
        return
    if facts.get("error"):
        click.echo(f"cache file: {facts['file']} ({facts['error']})")
    else:
        click.echo(f"cache file: {facts['file']}, {facts['entries']} entries, {facts['bytes'] / 1e6:.1f} MB")
    click.echo(f"roadmaps: {len(roadmaps)}")


@cache.command("clear")
@click.option(
    "--cache-dir",
    type=click.Path(path_type=Path, file_okay=False),
    help="Cache directory (default: $XDG_CACHE_HOME/tmpnav).",
)
@report_errors
def cache_clear(cache_dir: Path | None) -> None:
    """Delete every cached cost and roadmap."""
    from tmpnav.oracle.cache import clear, default_cache_dir

    directory = cache_dir or default_cache_dir()
    removed = clear(directory)
    roadmaps = list((directory / "roadmaps").glob("*.npz")) if (directory / "roadmaps").exists() else []
    for p in roadmaps:
        p.unlink(missing_ok=True)
    click.echo(f"cleared {directory}: {removed} cache file(s), {len(roadmaps)} roadmap(s)")


@cli.command()
@SCENARIO_ARG
@click.option("--sessions", type=click.IntRange(min=1), default=25, show_default=True, help="Simulated executions.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the simulated noise.")
@output_option(True, "Directory for errors.csv, errors.png, summary.md.")
@click.option(
    "--replan",
    is_flag=True,
    help="Run the task planner even if the cache remembers its plan for this exact problem.",
)
@oracle_options
@report_errors
def simulate(scenario: Path, sessions: int, seed: int, output: Path | None, **kw: Any) -> None:
    """Execute the plan in simulation, with and without mutual observations.

    Each session samples the true initial poses from the initial beliefs, applies noisy
    controls (a waypoint follower steering on the estimate) and noisy observations, and
    runs the EKF with mutual observations (config 1) and without (config 2), on the same
    random draws. Prints the worst-case position error per robot and its reduction.
    """
    from tmpnav.bench.simulate import simulate as run_simulation
    from tmpnav.bench.simulate import summary_lines, to_csv
    from tmpnav.pipeline import plan as run_plan

    options = plan_options(kw)
    report = run_plan(scenario, options)
    result = run_simulation(report, sessions, seed)
    lines = summary_lines(result, sessions)
    if output is not None:
        from tmpnav.bench.bench import write_atomic
        from tmpnav.report.bench_plot import plot_errors

        with writing(output):
            write_atomic(output / "errors.csv", to_csv(result, report))
            plot_errors(
                result,
                output / "errors.png",
                f"{report.scenario.name}: average position error over {sessions} sessions",
            )
            write_atomic(output / "summary.md", "\n".join(lines) + "\n")
        lines += [f"wrote {output / name}" for name in ("errors.csv", "errors.png", "summary.md")]
    click.echo("\n".join(lines))


@cli.command()
@click.option(
    "--rooms",
    "rooms_text",
    default="2..10",
    show_default=True,
    help="Rooms to visit: a range A..B[:STEP] (step 2 by default) or a list A,B,C.",
)
@click.option(
    "--robots",
    "robots_text",
    default="2",
    show_default=True,
    help="Robots: a range or a list; several values make a robots experiment.",
)
@click.option(
    "--sessions",
    type=click.IntRange(min=1),
    default=25,
    show_default=True,
    help="Sessions (random goal draws) per point.",
)
@click.option(
    "--encoding",
    "encodings",
    multiple=True,
    type=click.Choice(["paper", "single", "mixed"]),
    help="Encodings to compare on the same draws (repeat the option); default: mixed.",
)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the goal draws.")
@click.option(
    "--timeout",
    type=click.FloatRange(min=0, min_open=True),
    default=300.0,
    show_default=True,
    help="Seconds a run may take before it is recorded as a timeout.",
)
@click.option(
    "--scenario",
    type=click.Path(path_type=Path, dir_okay=False),
    help="World to use; {robots} in it becomes the number of robots (default: configs/corridor-{robots}robots.yaml).",
)
@click.option("--workers", type=click.IntRange(min=1), help="Oracle worker processes per run (default: all cores).")
@output_option(True, "Directory for bench.csv, bench.png, summary.md.", default=Path("bench-out"), show_default=True)
@click.option("-q", "--quiet", is_flag=True, help="No progress lines.")
@click.option(
    "--replot",
    is_flag=True,
    help="Run nothing: rewrite summary.md and bench.png from the bench.csv in -o DIR (give the run's --timeout).",
)
@report_errors
def bench(
    rooms_text: str,
    robots_text: str,
    sessions: int,
    encodings: tuple[str, ...],
    seed: int,
    timeout: float,
    scenario: Path | None,
    workers: int | None,
    output: Path,
    quiet: bool,
    replot: bool,
) -> None:
    """Planning time against the number of rooms (Fig. 3(b)) or of robots (Fig. 3(c)).

    Every run plans in its own process: cold (empty cache), warm (cost table and task
    plan from the cache) and replan (cost table from the cache, the task planner runs
    again); runs longer than --timeout are recorded as timeouts. Writes bench.csv,
    bench.png and summary.md.
    """
    from tmpnav.bench import bench as b
    from tmpnav.report.bench_plot import plot_bench
    from tmpnav.scenario import load

    written = ["bench.png", "summary.md"]
    if replot:
        table = b.read_csv(output / "bench.csv")
        experiment = str(table[0]["experiment"])
        encs = list(dict.fromkeys(str(r["encoding"]) for r in table))
        sessions = len({r["session"] for r in table})
    else:
        rooms, robots = b.parse_counts(rooms_text, "--rooms"), b.parse_counts(robots_text, "--robots")
        experiment = "robots" if len(robots) > 1 else "rooms"
        encs = list(encodings) or ["mixed"]
        for n in robots:  # bad input is reported before an hour of benchmarking, not after
            load(b.scenario_for(n, scenario))
        job_list = b.jobs(
            experiment,
            robots,
            rooms,
            sessions,
            encs,
            seed,
            scenario,
            lambda path: [room.name for room in load(path).rooms],
        )
        say = None if quiet else (lambda line: click.echo(line, err=True))
        table = b.run_bench(job_list, timeout, workers, say)
        with writing(output):
            b.write_atomic(output / "bench.csv", b.to_csv(table))
        written.insert(0, "bench.csv")
    axis = experiment
    med = b.medians(table, axis)
    text = f"# tmpnav bench: {experiment}\n\n" + b.summary(table, axis, default=encs[0], timeout=timeout)
    per_point = f"{sessions} session{'s' if sessions != 1 else ''} per point"
    with writing(output):
        b.write_atomic(output / "summary.md", text)
        plot_bench(med, axis, output / "bench.png", f"planning time against {axis} ({per_point})", timeout)
    click.echo(text)
    for name in written:
        click.echo(f"wrote {output / name}")


@cli.command()
@report_errors
def doctor() -> None:
    """Check that everything tmpnav runs on is here (Java 17+ for ENHSP, OMPL, numba)."""
    from importlib.metadata import version

    from tmpnav.task.solve import JAVA_MIN, check_java, java_version

    check_java()
    click.echo(f"java: {java_version()} (ENHSP needs {JAVA_MIN}+): ok")
    for package in ("unified-planning", "up-enhsp", "ompl", "filterpy", "numba", "numpy"):
        click.echo(f"{package}: {version(package)}")


@cli.command()
@report_errors
def reference() -> None:
    """Print the scenario format reference (every key, unit, default) as Markdown."""
    from tmpnav.scenario.reference import markdown

    click.echo(markdown(), nl=False)


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
    a traceback (click's own usage errors included: ``error: ... (see 'tmpnav plan --help')``)."""
    import warnings

    warnings.showwarning = _one_line_warning
    try:
        code = cli.main(prog_name="tmpnav", standalone_mode=False)
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
    except click.Abort:
        click.echo("error: interrupted", err=True)
        sys.exit(130)
    sys.exit(code if isinstance(code, int) else 0)
