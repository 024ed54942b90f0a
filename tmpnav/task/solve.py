"""Stage 6b: run a unified-planning engine (ENHSP by default) on the encoded problem.

Every failure becomes a typed :class:`~tmpnav.errors.PlannerError` with its own exit code:
no Java, unknown engine, timeout, proved unsolvable, crashed.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

from tmpnav.errors import (
    PlannerCrashError,
    PlannerError,
    PlannerTimeoutError,
    PlannerUnavailableError,
    UnsolvableError,
)
from tmpnav.types import PlanStatus

if TYPE_CHECKING:
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

JAVA_MIN = 17

#: JVM options for ENHSP's short runs: the C1 compiler alone starts faster, which saves
#: 0.2-0.3 s a run (measured in benchmarks/); TMPNAV_JAVA_OPTIONS replaces them.
JAVA_OPTIONS = "-XX:TieredStopAtLevel=1 -XX:+UseSerialGC"


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


@functools.lru_cache(maxsize=1)
def java_version() -> int | None:
    """The major version of the ``java`` on PATH, or None if there is none."""
    java = shutil.which("java")
    if java is None:
        return None
    try:
        out = subprocess.run([java, "-version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    match = re.search(r'version "(\d+)(?:\.(\d+))?', out.stderr + out.stdout)
    if match is None:
        return None
    major = int(match.group(1))
    return int(match.group(2) or 0) if major == 1 else major  # "1.8" means Java 8


def check_java() -> None:
    """Raise PlannerUnavailableError unless a Java 17+ is on PATH (ENHSP is a Java program)."""
    version = java_version()
    if version is None:
        raise PlannerUnavailableError(
            "Java was not found on PATH; ENHSP needs Java 17 or newer "
            "(Debian/Ubuntu: apt-get install openjdk-17-jre-headless)"
        )
    if version < JAVA_MIN:
        raise PlannerUnavailableError(f"Java {version} found on PATH; ENHSP needs Java {JAVA_MIN} or newer")


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


def solve(problem: Problem, planner: str, timeout: float) -> SolveResult:
    """Run ``planner`` on ``problem`` within ``timeout`` seconds; raise on any failure."""
    from unified_planning.engines import PlanGenerationResultStatus as St
    from unified_planning.exceptions import UPException

    env = environment()
    if planner not in env.factory.engines:
        raise PlannerUnavailableError(
            f"unknown planner {planner!r}; installed unified-planning planners: {', '.join(installed_planners())}"
        )
    if planner.startswith("enhsp"):
        check_java()
    try:
        engine_cls = env.factory.engine(planner)
    except Exception as err:
        raise PlannerUnavailableError(f"planner {planner!r} cannot be loaded: {err}") from None
    _freeze(problem)
    if not engine_cls.supports(problem.kind):
        raise PlannerUnavailableError(
            f"planner {planner!r} does not support this problem (it needs numeric fluents and action costs); "
            f"try enhsp-opt, enhsp or enhsp-blind"
        )
    import unified_planning.shortcuts as ups

    saved = os.environ.get("JAVA_TOOL_OPTIONS")
    os.environ["JAVA_TOOL_OPTIONS"] = os.environ.get("TMPNAV_JAVA_OPTIONS", JAVA_OPTIONS)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with ups.OneshotPlanner(name=planner) as engine:
                result = engine.solve(problem, timeout=timeout)
    except UPException as err:
        raise PlannerError(f"planner {planner!r} failed: {err}") from None
    except FileNotFoundError as err:
        raise PlannerUnavailableError(f"planner {planner!r} could not start: {err}") from None
    finally:
        if saved is None:
            os.environ.pop("JAVA_TOOL_OPTIONS", None)
        else:
            os.environ["JAVA_TOOL_OPTIONS"] = saved
    log = "\n".join(m.message for m in (result.log_messages or []) if "JAVA_TOOL_OPTIONS" not in m.message)
    tail = " | ".join(line.strip() for line in log.strip().splitlines()[-3:])
    status = result.status
    if status == St.TIMEOUT:
        raise PlannerTimeoutError(
            f"planner {planner!r} found no plan within the time limit of {timeout:g} s (--timeout)"
        )
    if status in (St.UNSOLVABLE_PROVEN, St.UNSOLVABLE_INCOMPLETELY):
        raise UnsolvableError(
            f"planner {planner!r} found no plan: the goals cannot be reached with the moves the roadmap allows "
            "(a goal room that its robot cannot reach?)"
        )
    if status == St.UNSUPPORTED_PROBLEM:
        raise PlannerUnavailableError(f"planner {planner!r} does not support this problem")
    if status not in (St.SOLVED_OPTIMALLY, St.SOLVED_SATISFICING) or result.plan is None:
        detail = f": {tail}" if tail else ""
        raise PlannerCrashError(f"planner {planner!r} failed with status {status.name}{detail}")
    actions = tuple((a.action.name, tuple(str(p) for p in a.actual_parameters)) for a in result.plan.actions)
    plan_status = PlanStatus.SOLVED_OPTIMALLY if status == St.SOLVED_OPTIMALLY else PlanStatus.SOLVED_SATISFICING
    return SolveResult(plan_status, actions, result.engine_name, tail, result.plan)
