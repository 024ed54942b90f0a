"""The certified lower bound of a run's plan space, for the anytime search's gap."""

from __future__ import annotations

import math
import multiprocessing
import multiprocessing.process
import os
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from multiprocessing.connection import Connection
from typing import TypeAlias

from tmpnav.attachment.floors import FloorsStopped, motion_floors
from tmpnav.beside import WAIT_SLICE
from tmpnav.lifetime import signals_held
from tmpnav.oracle.executors import die_with_parent, library, name_process
from tmpnav.planning.run import TaskRun
from tmpnav.task.bound import CUT_ROUNDS, Bound, lower_bound, makespan_bound
from tmpnav.types import CostTable, Goals

#: paired moves beyond which the bound of the table gives way to the motion floors: bounding
#: each pair without joint simulation takes about 0.2 ms (20 rooms and 2 robots: 130,000 pairs)
MAX_BOUND_PAIRS = 25_000
#: under a time limit (--time-limit) the bound may take this share of the time left when it
#: starts: its rounds of cuts, then its motion floors, give way past it (the search's first
#: plan needs the rest)
BOUND_SHARE = 0.25
#: the relaxation named when the bound's share passed before its motion floors were computed
NO_FLOORS = "none: its share of --time-limit passed before the moves' motion floors were computed"


def certified_bound(run: TaskRun) -> Bound:
    """A lower bound on the objective of every plan of the anytime search's plan space.

    On the sum of action costs: with table costs and at most :data:`MAX_BOUND_PAIRS` paired
    moves possible, the bound of the table with every pair at its cost or its lower bound
    (:func:`tmpnav.task.bound.lower_bound`); otherwise, and with carried costs (where a move's
    cost depends on the beliefs it starts from), the bound of the moves' motion floors
    (:mod:`tmpnav.attachment.floors`), which hold in every context and for every paired move.
    When the objective prices time, plus its price of the makespan's lower bound from the
    moves' time floors and the jobs' services and windows (:func:`tmpnav.task.bound.makespan_bound`:
    each goal's least round trip of a robot that may serve it, from its start to its end; or
    :func:`_work_bound` where higher): both bounds hold for every plan at once, so their
    weighted sum bounds its objective."""
    sp, goals, canonical = run.planner, run.goals, run.canonical
    stop = stop_at_share(run.search.deadline.left())
    # with carried beliefs a robot leaves a room with the heading it arrived with
    arrived = run.choice.costs == "carried"
    paths = library(canonical.oracle.ctx).graph
    try:
        floors = motion_floors(run.scenario, paths, canonical.start_location, goals, arrived, stop)
    except FloorsStopped:  # every cost and time is at least 0
        return Bound(0.0, NO_FLOORS, {"potentials": 0.0, "assignment": 0.0, "flow": 0.0}, stopped=True)
    bound = None
    if run.choice.costs == "table":
        table = canonical.bound_table(goals, MAX_BOUND_PAIRS)
        if table is not None:
            if sp.encoding != "mixed":
                table = replace(table, pair={})
            bound = lower_bound(table, goals, sp.pair_min_gain, stop=stop)
    # a replan (its incumbent the plan under way) has a short budget: the plain LP, no cuts
    rounds = 0 if run.incumbent else CUT_ROUNDS
    if bound is None:
        bound = lower_bound(floors, goals, 0.0, rounds, stop)
        bound = replace(bound, relaxation=f"motion floors, {bound.relaxation}")
    if not run.span_weight:
        return _said(bound)
    timed = floors.with_service(goals)  # a move's time until its robot is free again
    spent = stop is not None and stop()  # its share spent: no LP more (each holds the first plan back)
    work = WorkBound(0.0, True) if spent else _work_bound(timed, goals, rounds, stop)
    span = max(makespan_bound(timed, goals), work.value)
    value = bound.value + run.span_weight * span
    parts = {**bound.parts, "makespan": span}
    relaxation = f"{bound.relaxation} + makespan floor {span:.1f} s"
    return _said(replace(bound, value=value, relaxation=relaxation, parts=parts, stopped=bound.stopped or work.stopped))


#: the bound's process's pipe: ("bound", Bound) or ("error", an exception or its words)
_Pipe: TypeAlias = "Connection[tuple[str, object], tuple[str, object]]"


class LaterBound:
    """:func:`certified_bound` computed in a process of its own, forked once the search has its
    single moves' costs (:meth:`start`): with carried costs it reads only the roadmap's shortest
    paths (the moves' motion floors), no oracle, and from then on the run works on one core
    (OR-Tools' first routes, the first plans' pricing) while the other is idle. The search asks
    for it when it first tells of a plan (:meth:`__call__`); the run's ``bound`` stage is the
    time it then waits for it. Its value is the one computed in line, so is the plan.

    A process, not a thread: the bound's Python work beside the main thread took the
    interpreter's lock from it in 5 ms turns, and the main thread's many short waits (the
    oracle's results, OR-Tools' callbacks) each waited a turn (office, 100 rooms, 16 robots: the
    run 6 s slower, not 16 s faster). Where forking is not available it is computed in line."""

    def __init__(self, run: TaskRun):
        self._run = run
        self._value: Bound | None = None
        self._process: multiprocessing.process.BaseProcess | None = None
        self._reader: _Pipe | None = None

    def start(self) -> None:
        """Fork the bound's process (once; nothing where the platform cannot fork)."""
        if self._process is not None or "fork" not in multiprocessing.get_all_start_methods():
            return
        oracle = self._run.canonical.oracle
        if not self._run.scenario.models.partners_fused:
            # no paired moves to cost: the single moves' table was the workers' last wave (the
            # search asks for a move at a time, computed in this process); their memory is let
            # go before the bound's process forks beside them
            oracle.let_go_of_workers()
        library(oracle.ctx)  # the paths' library, made before the fork
        fork = multiprocessing.get_context("fork")
        self._reader, writer = fork.Pipe(duplex=False)
        process = fork.Process(target=_forked, args=(self._run, writer, os.getpid()), name="tmpnav-bound", daemon=True)
        with signals_held():
            process.start()
        writer.close()
        self._process = process

    def __call__(self) -> Bound:
        """The bound (the wait for its process timed as the ``bound`` stage)."""
        if self._value is None:
            with self._run.times.timed("bound"):
                self._value = self._wait() if self._process is not None else certified_bound(self._run)
        return self._value

    def _wait(self) -> Bound:
        reader, process = self._reader, self._process
        assert reader is not None and process is not None
        try:
            # in slices: a signal the kernel hands to another thread is run between them
            while not reader.poll(WAIT_SLICE):
                pass
            kind, value = reader.recv()
        except EOFError:  # its end of the pipe closed with nothing sent: the process died
            process.join()
            raise RuntimeError(f"the lower bound's process ended without one (exit code {process.exitcode})") from None
        finally:
            reader.close()
            if process.is_alive():
                process.kill()
            process.join()
        if kind == "error":
            raise value if isinstance(value, BaseException) else RuntimeError(f"the lower bound failed: {value}")
        assert isinstance(value, Bound)
        return value


def _forked(run: TaskRun, writer: _Pipe, parent: int) -> None:
    """The bound's process: :func:`certified_bound`, sent to the run (or its error, in words)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the run's business; it ends this process
    die_with_parent(parent)
    name_process("tmpnav-bound")
    try:
        writer.send(("bound", certified_bound(run)))
    except Exception as error:  # the run raises it where the bound is asked for
        try:
            writer.send(("error", error))
        except Exception:  # an error that does not pickle: in words
            writer.send(("error", f"{type(error).__name__}: {error}"))
    finally:
        writer.close()


def stop_at_share(left: float) -> Callable[[], bool] | None:
    """Whether the bound has spent its :data:`BOUND_SHARE` of the ``left`` seconds of the run's
    time limit; None without a limit (the bound then does all its work, the same on every
    machine)."""
    if not math.isfinite(left):
        return None
    until = time.perf_counter() + BOUND_SHARE * max(left, 0.0)
    return lambda: time.perf_counter() >= until


def _said(bound: Bound) -> Bound:
    """The bound, its relaxation saying when its share of the time limit cut its cuts short."""
    if not bound.stopped:
        return bound
    return replace(
        bound, relaxation=f"{bound.relaxation}; rounds of cuts cut short by the bound's share of --time-limit"
    )


def _work_bound(
    floors: CostTable, goals: Goals, rounds: int = CUT_ROUNDS, stop: Callable[[], bool] | None = None
) -> WorkBound:
    """A lower bound on every schedule's makespan: the relaxation of :func:`lower_bound` over
    the moves' time floors bounds the summed time of every plan's moves (the argument of
    tmpnav/task/bound.py holds for any non-negative move prices, and a paired move takes each
    of its robots at least its own floor), the robots share that driving and each is busy for
    at most the makespan, so the makespan is at least the sum over the number of robots."""
    durations = replace(floors, single={m: floors.duration[m] for m in floors.single if m in floors.duration})
    work = lower_bound(durations, goals, 0.0, rounds, stop)
    value = max(0.0, work.value) / max(1, len(floors.robots)) if math.isfinite(work.value) else 0.0
    return WorkBound(value, work.stopped)


@dataclass(frozen=True)
class WorkBound:
    """:func:`_work_bound`: the makespan's bound (s), and whether a stop cut its cuts short."""

    value: float
    stopped: bool
