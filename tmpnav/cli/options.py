"""What the commands of :mod:`tmpnav.cli.commands` share: error handling, the scenario argument,
output options checked before any work, the oracle's options, and the progress bar."""

from __future__ import annotations

import contextlib
import functools
import math
import os
import sys
import traceback
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from tmpnav.choices import COSTS, SEARCHES
from tmpnav.errors import OutputError, ScenarioError, TmpnavError
from tmpnav.lifetime import check_signals

if TYPE_CHECKING:
    from tmpnav.pipeline import PlanOptions


def report_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn library exceptions into one line per problem on stderr and an exit code.

    A bug prints one line too; set TMPNAV_DEBUG=1 to see its traceback.
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            try:
                return func(*args, **kwargs)
            except Exception:
                # after Ctrl-C or SIGTERM, whatever ends the run is the signal's doing: a C extension
                # imported at that instant fails as "ImportError: initialization failed" (tmpnav.lifetime)
                check_signals()
                raise
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
        except BrokenPipeError:  # the reader went away (tmpnav configs | head): nothing to report
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            sys.exit(1)
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


def _scenario(ctx: click.Context, param: click.Parameter, value: Path) -> Path:
    from tmpnav.shipped import PREFIX, resolve

    path = resolve(value)
    if not path.exists() and path.parts[:1] == (PREFIX,):
        raise click.BadParameter(
            f"{value} is neither a file here nor a scenario shipped with tmpnav ('tmpnav configs' lists them)",
            ctx=ctx,
            param=param,
        )
    return path


#: a scenario file; ``configs/NAME.yaml`` names a shipped one when there is no such file here
SCENARIO_ARG = click.argument("scenario", type=click.Path(path_type=Path, dir_okay=False), callback=_scenario)


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


def output_option(directory: bool, help_text: str, figure: bool = False, **kwargs: Any) -> Callable[..., Any]:
    """``-o/--output``, checked before any work is done (a directory, or a file; with
    ``figure``, a picture whose suffix names a format tmpnav writes)."""

    def check(ctx: click.Context, param: click.Parameter, value: Path | None) -> Path | None:
        if value is not None and (why := unwritable(value, directory) or (figure and not_a_picture(value))):
            raise click.BadParameter(why, ctx=ctx, param=param)
        return value

    kind = click.Path(path_type=Path, file_okay=not directory, dir_okay=directory)
    return click.option("-o", "--output", type=kind, callback=check, help=help_text, **kwargs)


def not_a_picture(path: Path) -> str | None:
    """Why ``path`` cannot name a picture (its suffix names no format tmpnav writes), or None."""
    from tmpnav.report import figure_format, figure_suffixes

    if figure_format(path.name) is None:
        return f"{path}: expected a picture file ending in {figure_suffixes()}"
    return None


@contextlib.contextmanager
def writing(output: Path) -> Iterator[None]:
    """Outputs that fail to write late (a full disk) are one line, not an internal error."""
    try:
        yield
    except OSError as err:
        target = err.filename or output
        raise OutputError(f"cannot write {target}: {err.strerror or err}") from None


class FiniteRange(click.FloatRange):
    """click's FloatRange without NaN and infinities: NaN compares false with every bound,
    so FloatRange let ``--pair-min-gain nan`` through (and it dropped every paired move)."""

    name = "finite float range"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = click.FLOAT.convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return super().convert(number, param, ctx)


def timeout_range() -> FiniteRange:
    """Seconds: more than 0, at most the scenario format's limit (planner.timeout)."""
    from tmpnav.scenario.format import MAX_TIMEOUT

    return FiniteRange(min=0, min_open=True, max=MAX_TIMEOUT)


def encoding_choice() -> click.Choice:
    """The task encodings (tmpnav.choices.ENCODINGS)."""
    from tmpnav.choices import ENCODINGS

    return click.Choice(list(ENCODINGS))


def oracle_options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Options shared by every command that computes action costs."""
    options = [
        click.option("--encoding", type=encoding_choice(), help="Task encoding (overrides planner.encoding)."),
        click.option(
            "--planner",
            "planner_name",
            metavar="NAME",
            help="unified-planning engine (overrides planner.name), e.g. enhsp-blind (default), enhsp-opt, enhsp.",
        ),
        click.option("--timeout", type=timeout_range(), metavar="S", help="Planner time limit in seconds."),
        click.option(
            "--search",
            type=click.Choice(list(SEARCHES)),
            help="Task-level search: exact, anytime (ENHSP on sub-problems, with a lower bound) or auto "
            "(exact where it finishes quickly; the default, or planner.search).",
        ),
        click.option(
            "--time-budget",
            type=timeout_range(),
            metavar="S",
            help="Anytime search: seconds for the whole run (default: planner.time_budget, or 0.25 s per goal "
            "room and robot, 10-180 s).",
        ),
        click.option(
            "--costs",
            type=click.Choice(list(COSTS)),
            help="Action costs: table (canonical start states) or carried (the beliefs the robots carry).",
        ),
        click.option(
            "--pair-min-gain",
            type=FiniteRange(0, 1),
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
            help="Cache directory: costs, roadmaps, task plans (default: $TMPNAV_CACHE_DIR or $XDG_CACHE_HOME/tmpnav).",
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


def plan_options(kw: dict[str, Any]) -> PlanOptions:
    """The pipeline's options from the values of :func:`oracle_options` (and ``--replan``)."""
    from tmpnav.pipeline import Execution, Overrides, PlanOptions, Reporters

    overrides = Overrides(
        encoding=kw["encoding"],
        planner=kw["planner_name"],
        timeout=kw["timeout"],
        pair_min_gain=kw["pair_min_gain"],
        mutual_observations=False if kw["no_mutual_observations"] else None,
        search=kw["search"],
        time_budget=kw["time_budget"],
        costs=kw["costs"],
    )
    execution = Execution(
        cache_dir=kw["cache_dir"],
        use_cache=not kw["no_cache"],
        replan=kw.get("replan", False),
        executor=kw["executor"],
        workers=kw["workers"],
        ray_address=kw["ray_address"],
    )
    quiet = kw["quiet"]
    reporters = Reporters(None if quiet else progress_bar("oracle"), None if quiet else search_progress())
    return PlanOptions(overrides, execution, reporters)


def search_progress() -> Callable[[float, float, float | None, str], None]:
    """The anytime search's progress on stderr: elapsed time, best cost, lower bound, gap.
    On a terminal one line is rewritten in place; otherwise a line per event."""
    tty = sys.stderr.isatty()

    def show(seconds: float, best: float, bound: float | None, what: str) -> None:
        text = f"search {seconds:7.1f} s  best {best:12.3f}"
        if bound is not None:
            gap = max(0.0, (best - bound) / best) if best > 0 else 0.0
            text += f"  bound {bound:12.3f}  gap {100 * gap:5.1f}%"
        text += f"  ({what})"
        if tty:
            sys.stderr.write("\r\033[K" + text)
        else:
            sys.stderr.write(text + "\n")
        sys.stderr.flush()

    return show


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


CACHE_DIR_OPTION = click.option(
    "--cache-dir",
    type=click.Path(path_type=Path, file_okay=False),
    help="Cache directory (default: $TMPNAV_CACHE_DIR or $XDG_CACHE_HOME/tmpnav).",
)
