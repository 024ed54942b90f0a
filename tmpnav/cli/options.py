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

from tmpnav.choices import COSTS, OBJECTIVES, SEARCHES
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
    return option("-o", "--output", type=kind, callback=check, help=help_text, **kwargs)


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


class ThresholdOrNone(FiniteRange):
    """A probability in (0, 1], or ``none``: no chance constraint (NO_THRESHOLD)."""

    name = "threshold"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and value.strip().lower() == "none":
            from tmpnav.pipeline import NO_THRESHOLD

            return NO_THRESHOLD
        return super().convert(value, param, ctx)


def timeout_range() -> FiniteRange:
    """Seconds: more than 0, at most the scenario format's limit (planner.timeout)."""
    from tmpnav.scenario.format import MAX_TIMEOUT

    return FiniteRange(min=0, min_open=True, max=MAX_TIMEOUT)


def encoding_choice() -> click.Choice:
    """The task encodings (tmpnav.choices.ENCODINGS)."""
    from tmpnav.choices import ENCODINGS

    return click.Choice(list(ENCODINGS))


class Option(click.Option):
    """A click option whose help says its default in words where click cannot (``default_text``:
    a default that comes from the scenario, or is computed), and that keeps earlier names
    working (``old``: scripts use them) without showing them in ``--help``."""

    def __init__(
        self,
        *args: Any,
        default_text: str | None = None,
        old: tuple[str, ...] = (),
        hide_range: bool = False,
        **kwargs: Any,
    ):
        super().__init__(*args, **kwargs)
        self.default_text = default_text
        self.old_names = old
        self.hide_range = hide_range

    def get_help_record(self, ctx: click.Context) -> tuple[str, str] | None:
        shown, self.opts = self.opts, [o for o in self.opts if o not in self.old_names]
        try:
            return super().get_help_record(ctx)
        finally:
            self.opts = shown

    def get_help_extra(self, ctx: click.Context) -> Any:
        extra = super().get_help_extra(ctx)
        if self.default_text is not None:
            extra["default"] = self.default_text
        if self.hide_range:
            extra.pop("range", None)
        return extra


def option(*decls: str, old: tuple[str, ...] = (), **kwargs: Any) -> Any:
    """``click.option`` with :class:`Option` (``default_text``, ``old`` hidden names, ``hide_range``)."""
    return click.option(*decls, *old, cls=Option, old=old, **kwargs)


def seconds_option(*decls: str, **kwargs: Any) -> Any:
    """An option of seconds, more than 0 (its range, up to the format's 1e6 s, is left out of the help)."""
    return option(*decls, type=timeout_range(), metavar="S", hide_range=True, **kwargs)


def scenario_default(key: str, fallback: str | None = None) -> str:
    """``"the scenario's planner.KEY, else DEFAULT"``: the default of an option that overrides a
    scenario key, with the format's own default (tmpnav.scenario.format)."""
    from tmpnav.scenario.format import PLANNER

    value = PLANNER.fields[key].default
    shown = fallback if fallback is not None else (f"{value:g}" if isinstance(value, float) else str(value))
    return f"the scenario's planner.{key}, else {shown}"


def oracle_options(func: Callable[..., Any] | None = None, mutual: bool = True) -> Any:
    """Options shared by every command that computes action costs; without ``mutual``, no
    ``--no-mutual-observations`` (``tmpnav simulate`` runs both configurations itself)."""
    if func is None:
        return lambda f: oracle_options(f, mutual)
    options = [
        option(
            "--encoding",
            type=encoding_choice(),
            default_text=scenario_default("encoding"),
            help="How moves become planner actions: paper (every action moves two robots, as in the paper), "
            "single (one robot per action) or mixed (single moves, plus the paired moves that save cost "
            "because the two robots see each other).",
        ),
        option(
            "--planner",
            "planner_name",
            metavar="NAME",
            default_text=scenario_default("name"),
            help="Task planner, a unified-planning engine: enhsp-blind or enhsp-opt (optimal), enhsp "
            "(faster, not optimal), or another installed engine that supports the problem.",
        ),
        seconds_option(
            "--planner-timeout",
            "timeout",
            old=("--timeout",),
            default_text=scenario_default("timeout"),
            help="Seconds one run of the task planner (ENHSP) may take: an exact search that needs longer "
            "fails (exit code 5); the anytime search gives up that sub-problem and goes on.",
        ),
        option(
            "--search",
            type=click.Choice(list(SEARCHES)),
            default_text=scenario_default("search"),
            help="How the task plan is searched: exact (one optimal search over all plans), anytime (a first "
            "plan improved piece by piece until --anytime-work, with a lower bound on the best cost) or auto "
            "(exact where that finishes quickly).",
        ),
        option(
            "--anytime-work",
            "work_budget",
            type=click.IntRange(min=1, max=10**6),
            metavar="N",
            default_text=scenario_default("work_budget", "2 per goal room and robot, from 50 to 1000"),
            help="The anytime search's budget in work: the ENHSP sub-problems it may solve; then it returns its "
            "best plan (not an error). Counted in work, not seconds, so the same scenario gives the same plan on "
            "any machine. Ignored by the exact search.",
        ),
        seconds_option(
            "--anytime-budget",
            "time_budget",
            old=("--time-budget",),
            default_text=scenario_default("time_budget", "none"),
            help="A time cap on the anytime search (seconds of the whole run); past it, its best plan, and the "
            "summary and plan.json say that the time cap ended the search (a plan of the machine's speed).",
        ),
        seconds_option(
            "--routing-time",
            "routing_time",
            default_text=scenario_default("routing_time", "a quarter of the anytime search's time cap, at most 30"),
            help="OR-Tools' time limit on the anytime search's first routes. Their count of solutions should "
            "end them: where the limit does (200 places and 32 robots take about 2 minutes for 500), the plan is "
            "the machine's and the summary says so; a longer limit gives the same plan on any machine.",
        ),
        seconds_option(
            "--time-limit",
            "time_limit",
            default_text=scenario_default("time_limit", "none"),
            help="Seconds the whole command may take: past it, the best plan found so far (simulate: the "
            "executions done so far); with no plan yet, exit code 5 naming the stage that took the time.",
        ),
        option(
            "--costs",
            type=click.Choice(list(COSTS)),
            default_text=scenario_default("costs"),
            help="What a move costs the planner: carried (from the beliefs the robots carry at that point of "
            "the plan, as executed) or table (from one fixed start belief per room: faster, less exact).",
        ),
        option(
            "--objective",
            type=click.Choice(list(OBJECTIVES)),
            default_text=scenario_default(
                "objective", "makespan for a team on a shift or a fleet of 9 robots or more, weighted otherwise"
            ),
            help="What the plan minimises, the robots moving at once: weighted (the costs of all moves plus "
            "cost.M_T per second until the last robot is done), cost (the costs of all moves, as in the paper) "
            "or makespan (the time until the last robot is done first).",
        ),
        option(
            "--min-rooms",
            type=click.IntRange(min=0, max=10**4),
            metavar="N",
            default_text=scenario_default("min_rooms", "3 for a fleet of 9 robots or more, else 0"),
            help="Every robot visits at least N goal rooms (fewer where the goals give fewer per robot), so "
            "that none stands idle while others work; a plan that cannot keep to it is ranked below all "
            "that do, and the summary names the robots short of it. Planned by the anytime search. "
            "0: no minimum.",
        ),
        option(
            "--max-risk",
            type=ThresholdOrNone(min=0, min_open=True, max=1),
            metavar="DELTA",
            default_text="the scenario's planner.max_risk, else 0.05 for robots with a range sensor, else none",
            help="The chance constraint: the largest probability of collision a move may have (its bound on "
            "touching a wall, from the robot's uncertainty along the path and the map's clearance; robots "
            "also keep a margin from each other for it). Moves over it are not offered to the planner, and "
            "robots in each other's way are kept apart by waits, detours and sidesteps where every move "
            "stays within it. 'none': no chance constraint.",
        ),
        option(
            "--clearance",
            type=FiniteRange(min=0, max=5),
            metavar="M",
            default_text="the scenario's roadmap.clearance, else 0.5 with a range sensor or a threshold, else 0",
            help="The margin from the walls (m, beyond the robot's radius) that paths prefer and goal poses "
            "keep, as nav2's inflation does, with roadmap nodes through the middle of every passage narrower "
            "than it (doors); 0 gives the paper's shortest paths.",
        ),
        click.option(
            "--accept-risk",
            is_flag=True,
            help="Take the plan even when no plan keeps every move within the chance constraint, or robots "
            "stay in each other's way (exit codes 9 and 10 otherwise): the summary warns of it.",
        ),
        option(
            "--keep-apart/--no-keep-apart",
            default=None,
            default_text=scenario_default("keep_apart", "true"),
            help="Keep robots out of each other's way on the team's clock (the anytime search prices every "
            "plan so; an exact plan that keeping apart makes dearer is searched on so): a move held back "
            "(a wait), driven along another roadmap path around the other robot (a detour) or made through a "
            "room no goal names (a sidestep), if that costs at most 1.5 times the plan's objective (under "
            "--max-risk: if every move stays within it). --no-keep-apart: the plan as planned, its conflicts "
            "reported (the paper's model).",
        ),
        option(
            "--pair-min-gain",
            type=FiniteRange(0, 1),
            metavar="G",
            default_text=scenario_default("pair_min_gain"),
            help="Mixed encoding: offer two robots a joint move only if it costs at least this fraction less "
            "than their two moves alone (0: every pair that saves anything; the plan is then exact).",
        ),
        *(
            [
                click.option(
                    "--no-mutual-observations",
                    is_flag=True,
                    help="Plan as if the robots could not see each other (the paper's config 2).",
                )
            ]
            if mutual
            else []
        ),
        click.option(
            "--no-range-sensor",
            is_flag=True,
            help="Plan as if the robots had no range sensor, whatever the scenario's models.range_sensor "
            "(the paper's model: landmarks and partners only).",
        ),
        option(
            "--cache-dir",
            type=click.Path(path_type=Path, file_okay=False),
            default_text="$TMPNAV_CACHE_DIR, else ~/.cache/tmpnav",
            help="Where computed costs, roadmaps and task plans are kept for the next runs.",
        ),
        click.option("--no-cache", is_flag=True, help="Compute every cost afresh and store nothing."),
        option(
            "--workers",
            type=click.IntRange(min=1),
            metavar="N",
            default_text="one per core",
            help="Worker processes that compute the costs of moves (and run the sessions of tmpnav simulate).",
        ),
        option(
            "--executor",
            type=click.Choice(["processes", "serial", "ray"]),
            default="processes",
            show_default=True,
            help="Where the costs of moves are computed: processes (local workers), serial (this process) "
            "or ray (a Ray cluster; pip install 'tmpnav[ray]').",
        ),
        option(
            "--ray-address",
            metavar="ADDR",
            default_text="start a local Ray instance",
            help="Ray cluster to join with --executor ray.",
        ),
        click.option("-q", "--quiet", is_flag=True, help="No progress lines on stderr."),
    ]
    for decorator in reversed(options):
        func = decorator(func)
    return func


def plan_options(kw: dict[str, Any]) -> PlanOptions:
    """The pipeline's options from the values of :func:`oracle_options` (and ``--replan``)."""
    from tmpnav.pipeline import Execution, Overrides, PlanOptions, Reporters

    overrides = Overrides(
        encoding=kw["encoding"],
        planner=kw["planner_name"],
        timeout=kw["timeout"],
        pair_min_gain=kw["pair_min_gain"],
        mutual_observations=False if kw.get("no_mutual_observations") else None,
        range_sensor=False if kw.get("no_range_sensor") else None,
        search=kw["search"],
        time_budget=kw["time_budget"],
        work_budget=kw["work_budget"],
        routing_time=kw.get("routing_time"),
        time_limit=kw["time_limit"],
        costs=kw["costs"],
        objective=kw["objective"],
        min_rooms=kw.get("min_rooms"),
        max_risk=kw["max_risk"],
        keep_apart=kw.get("keep_apart"),
        accept_risk=bool(kw.get("accept_risk")),
        clearance=kw.get("clearance"),
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
    """The anytime search's progress on stderr: the run's time, best cost, lower bound, gap. On a
    terminal one line is rewritten in place; otherwise a line per event.

    The time is the run's clock (tmpnav.results.StageTimes.elapsed), the one its summary's
    ``total`` ends: it counts from the end of ``load``, through every phase of the search.
    """
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


CACHE_DIR_OPTION = option(
    "--cache-dir",
    type=click.Path(path_type=Path, file_okay=False),
    default_text="$TMPNAV_CACHE_DIR, else ~/.cache/tmpnav",
    help="The cache directory.",
)
