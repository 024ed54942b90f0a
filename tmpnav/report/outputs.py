"""The output folders: ``tmpnav plan -o DIR`` (plan.json, plan.png, schedule.png and the PDDL
files) and ``tmpnav simulate -o DIR`` (errors.csv, errors.png, summary.md), each written all or nothing.

The files of a folder are one group for :func:`tmpnav.atomic.write_files`: a reader never sees a partial
plan.json, nor a plan.png or schedule.png of another plan than the plan.json beside it, and a run
that fails while writing leaves the files of the earlier run as they were.

schedule.png is drawn in a process forked for it (:class:`DrawnAside`) while this one draws
plan.png: matplotlib draws on one core, and a plan's two figures are much of a warm command's time.
"""

from __future__ import annotations

import io
import multiprocessing
import os
import signal
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, BinaryIO

from tmpnav.atomic import Content, write_files
from tmpnav.errors import OutputError
from tmpnav.lifetime import signals_held
from tmpnav.oracle.executors import die_with_parent
from tmpnav.report import figures as fg
from tmpnav.report.plan_json import dumps, plan_document
from tmpnav.report.plan_plot import plan_figure
from tmpnav.report.schedule_plot import schedule_figure
from tmpnav.results import PlanReport
from tmpnav.task.export import PDDL_FILES

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from tmpnav.execution import ExecutionResult

    #: what the drawing child sends: the picture's bytes, or the error it raised
    Pipe = Connection[bytes | BaseException, bytes | BaseException]

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
    with DrawnAside(SCHEDULE_PNG, lambda out: fg.render(schedule_figure(report), out)) as schedule:
        contents: dict[str, Content] = {
            PLAN_JSON: dumps(plan_document(report)),
            PLAN_PNG: lambda tmp: fg.render(plan_figure(report), tmp),
            SCHEDULE_PNG: schedule.write,
        }
        if pddl is not None:
            contents.update(zip(PDDL_FILES, pddl, strict=True))
        contents.update(extra or {})
        return write_files(out_dir, contents)


class DrawnAside:
    """The picture ``name`` drawn by ``draw(file)`` in a child process forked on entry, while this
    process goes on; :meth:`write` waits for it and writes it to the path it is given (a temporary file
    of the group, so a child that fails fails the group). On exit the child is ended and
    reaped, whatever happened, so none outlives the write.

    :meth:`write` draws the picture itself where fork is missing, where this is not the main
    thread (a library caller's: other threads of its process may hold locks mid-way, which a
    fork would copy), and where no core is idle (:func:`core_to_spare`). The threads tmpnav runs
    beside a plan (ENHSP's answer reader) touch nothing the child does."""

    def __init__(self, name: str, draw: Callable[[BinaryIO], None]) -> None:
        self.name = name
        self.draw = draw
        self.child: multiprocessing.process.BaseProcess | None = None
        self.reader: Pipe | None = None

    def __enter__(self) -> DrawnAside:
        if (
            "fork" not in multiprocessing.get_all_start_methods()
            or threading.current_thread() is not threading.main_thread()
            or not core_to_spare()
        ):
            return self
        mp = multiprocessing.get_context("fork")
        reader, writer = mp.Pipe(duplex=False)
        with signals_held():  # started and recorded as one step: an interrupt between leaked it
            self.child = mp.Process(target=_draw_child, args=(self.draw, writer, os.getpid()), name="tmpnav-figure")
            self.child.start()
            self.reader = reader
        writer.close()
        return self

    def write(self, tmp: Path) -> None:
        """Write the picture to ``tmp``: the child's, once it is drawn, or drawn now."""
        if self.child is None or self.reader is None:
            with open(tmp, "wb") as fh:
                self.draw(fh)
            return
        try:
            value = self.reader.recv()
        except EOFError:
            self.child.join()
            raise OutputError(
                f"the process drawing {self.name} ended without it (exit status {self.child.exitcode})"
            ) from None
        if isinstance(value, BaseException):
            raise value
        tmp.write_bytes(value)

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        if self.child is None:
            return
        if self.child.is_alive() and error is not None:  # its picture is not wanted any more
            self.child.terminate()
        self.child.join()
        if self.reader is not None:
            self.reader.close()


def core_to_spare() -> bool:
    """Whether a core is idle now: fewer processes run than there are cores for this one, itself
    among them (Linux's count of running processes, /proc/loadavg). On a busy machine a child
    only queues behind the others, and the fork and the pages it copies cost more than it saves.
    True where the count is missing."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    try:
        with open("/proc/loadavg", encoding="ascii") as fh:
            running = int(fh.read().split()[3].partition("/")[0])
    except (OSError, ValueError, IndexError):
        return cores > 1
    return running < cores


def _draw_child(draw: Callable[[BinaryIO], None], writer: Pipe, parent: int) -> None:
    """In the forked child: draw, and send the picture's bytes or the error."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # the parent's handler came with the fork: just end
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business: it ends this one
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})  # held while the parent forked
    die_with_parent(parent)
    try:
        buffer = io.BytesIO()
        draw(buffer)
        writer.send(buffer.getvalue())
    except BaseException as e:  # the parent raises it
        try:
            writer.send(e)
        except Exception:  # an error that does not pickle: its text
            writer.send(OutputError(f"{type(e).__name__}: {e}"))
    finally:
        writer.close()


def write_execution_outputs(report: PlanReport, result: ExecutionResult, sessions: int, out_dir: Path) -> list[Path]:
    """``tmpnav simulate -o DIR``: errors.csv, sessions.csv (each session's makespan and waits),
        moves.csv (each move's wall hits and contacts against its bound), hits.csv (where and when each
        contact began), consistency.csv (each move's
    actual error against the localiser's and the plan's covariance), errors.png and summary.md,
        all or nothing."""
    from tmpnav.execution import error_summary, errors_csv
    from tmpnav.execution.consistency import csv_text
    from tmpnav.execution.text import hits_csv, moves_csv, sessions_csv
    from tmpnav.report.bench_plot import errors_figure

    title = f"{report.scenario.name}: average position error over {sessions} sessions"
    contents: dict[str, Content] = {
        "errors.csv": errors_csv(result, report.roadmap),
        "sessions.csv": sessions_csv(result),
        "moves.csv": moves_csv(result),
        "hits.csv": hits_csv(result),
        "errors.png": lambda tmp: fg.render(errors_figure(result, title), tmp),
        "consistency.csv": csv_text(result.consistency),
        "summary.md": "\n".join(error_summary(result, sessions)) + "\n",
    }
    return write_files(out_dir, contents)
