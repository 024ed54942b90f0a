"""The output folders: ``tmpnav plan -o DIR`` (plan.json, plan.png, schedule.png and the PDDL
files) and ``tmpnav simulate -o DIR`` (errors.csv, errors.png, summary.md), each written all or nothing.

The files of a folder are one group for :func:`tmpnav.atomic.write_files`: a reader never sees a partial
plan.json, nor a plan.png or schedule.png of another plan than the plan.json beside it, and a run
that fails while writing leaves the files of the earlier run as they were.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from tmpnav.atomic import Content, write_files
from tmpnav.report import figures as fg
from tmpnav.report.plan_json import dumps, plan_document
from tmpnav.report.plan_plot import plan_figure
from tmpnav.report.schedule_plot import schedule_figure
from tmpnav.results import PlanReport
from tmpnav.task.export import PDDL_FILES

if TYPE_CHECKING:
    from tmpnav.execution import ExecutionResult

PLAN_JSON = "plan.json"
PLAN_PNG = "plan.png"
SCHEDULE_PNG = "schedule.png"


def write_outputs(
    report: PlanReport, out_dir: Path, pddl: tuple[str, str] | None, extra: Mapping[str, Content] | None = None
) -> list[Path]:
    """Write plan.json, plan.png, schedule.png and, when ``pddl`` = (domain, problem) is given,
    domain.pddl and problem.pddl into ``out_dir`` (created if missing), with the ``extra`` files
    (names relative to ``out_dir``: ``nav2/r1.csv``) in the same group. Returns the paths
    written, in that order."""
    contents: dict[str, Content] = {
        PLAN_JSON: dumps(plan_document(report)),
        PLAN_PNG: lambda tmp: fg.render(plan_figure(report), tmp),
        SCHEDULE_PNG: lambda tmp: fg.render(schedule_figure(report), tmp),
    }
    if pddl is not None:
        contents.update(zip(PDDL_FILES, pddl, strict=True))
    contents.update(extra or {})
    return write_files(out_dir, contents)


def write_execution_outputs(report: PlanReport, result: ExecutionResult, sessions: int, out_dir: Path) -> list[Path]:
    """``tmpnav simulate -o DIR``: errors.csv, sessions.csv (each session's makespan and waits),
        moves.csv (each move's wall hits and contacts against its bound), consistency.csv (each move's
    actual error against the localiser's and the plan's covariance), errors.png and summary.md,
        all or nothing."""
    from tmpnav.execution import error_summary, errors_csv
    from tmpnav.execution.consistency import csv_text
    from tmpnav.execution.text import moves_csv, sessions_csv
    from tmpnav.report.bench_plot import errors_figure

    title = f"{report.scenario.name}: average position error over {sessions} sessions"
    contents: dict[str, Content] = {
        "errors.csv": errors_csv(result, report.roadmap),
        "sessions.csv": sessions_csv(result),
        "moves.csv": moves_csv(result),
        "errors.png": lambda tmp: fg.render(errors_figure(result, title), tmp),
        "consistency.csv": csv_text(result.consistency),
        "summary.md": "\n".join(error_summary(result, sessions)) + "\n",
    }
    return write_files(out_dir, contents)
