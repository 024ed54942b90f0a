"""Typed exceptions raised by library code.

Only :mod:`tmpnav.cli` turns them into messages and exit codes; nothing below the CLI
prints to the terminal or exits. Each class carries the exit code the CLI uses, so the
table in docs/usage.md and the code cannot drift apart (see ``EXIT_CODES``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file, reported on one line.

    ``path`` is the key path inside the file (``robots.r2.covariance``), empty for the
    whole file; ``line`` is the 1-based line in the file when known.
    """

    file: str
    path: str
    message: str
    line: int | None = None

    def __str__(self) -> str:
        where = self.file
        if self.line is not None:
            where += f":{self.line}"
        key = f" {self.path}:" if self.path else ""
        return f"{where}:{key} {self.message}"


class TmpnavError(Exception):
    """Base class of every error tmpnav reports to a user."""

    exit_code = 1


class InputError(TmpnavError):
    """Bad input: a scenario, a map, a command-line value (exit code 2)."""

    exit_code = 2


class OutputError(InputError):
    """An output file or directory (``-o``) cannot be written; nothing half-written is left."""


class ScenarioError(InputError):
    """A scenario (or a map it names) has one or more problems; all are listed."""

    def __init__(self, problems: list[Problem]):
        self.problems = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class RoadmapError(InputError):
    """The roadmap cannot serve the scenario (a room's instantiations do not connect)."""


class PlannerError(TmpnavError):
    """The task planner failed; subclasses say how."""

    exit_code = 3


class PlannerUnavailableError(PlannerError):
    """The planner cannot run here (no Java 17+, unknown or unsuitable engine)."""

    exit_code = 4


class PlannerTimeoutError(PlannerError):
    """The planner did not finish within the time limit."""

    exit_code = 5


class TimeLimitError(PlannerTimeoutError):
    """The run's time limit (--time-limit, planner.time_limit) passed before it had a plan; the
    message names the stage that took the time."""

    def __init__(self, message: str, limit: float):
        super().__init__(message)
        self.limit = limit


class UnsolvableError(PlannerError):
    """The planner proved that no plan reaches the goals."""

    exit_code = 6


class PlannerCrashError(PlannerError):
    """The planner process crashed or returned an unreadable answer."""

    exit_code = 7


class RiskError(PlannerError):
    """No plan keeps every move within the chance constraint (planner.max_risk)."""

    exit_code = 9

    def __init__(self, message: str, least: float):
        super().__init__(message)
        self.least = least  # the smallest threshold tmpnav found a plan for


class ConflictError(PlannerError):
    """The plan leaves robots in each other's way that keeping them apart could not clear."""

    exit_code = 10


class WindowError(PlannerError):
    """A job's window that no robot can arrive within (goals.jobs.window): its room, when it
    closes and the arrival found, on the clock of the plan (a revision's starts at its
    ``start_time``); ``certain``: the arrival is the earliest possible, so no plan meets the
    window (else it is the best plan's the search found)."""

    exit_code = 11

    def __init__(self, message: str, room: str = "", latest: float = 0.0, arrival: float = 0.0, certain: bool = False):
        super().__init__(message)
        self.room, self.latest, self.arrival, self.certain = room, latest, arrival, certain


#: ``tmpnav replan``: the revision is planned and written, but goals no robot can reach any more are left out
UNREACHABLE_GOALS = 12


class CacheError(TmpnavError):
    """The cache directory cannot be used at all (not a directory, not writable)."""

    exit_code = 8


#: exit code -> meaning, listed in docs/usage.md and printed in ``tmpnav --help``.
EXIT_CODES: dict[int, str] = {
    0: "success",
    1: "unexpected internal error (a bug: please report it)",
    InputError.exit_code: "bad input: scenario, map or command-line value (an output path that cannot be written too)",
    PlannerError.exit_code: "the planner failed for another reason",
    PlannerUnavailableError.exit_code: "no usable planner: Java 17+ missing, or unknown engine",
    PlannerTimeoutError.exit_code: "the planner timed out, or the run's --time-limit passed before it had a plan "
    "(the message names the stage that took the time)",
    UnsolvableError.exit_code: "no plan exists for the goals (proved by the planner)",
    PlannerCrashError.exit_code: "the planner process crashed",
    CacheError.exit_code: "the cache directory is unusable",
    RiskError.exit_code: "no plan keeps every move within the chance constraint (--max-risk, or its default): the "
    "message names the least threshold a plan meets and what would help; --accept-risk takes the plan",
    ConflictError.exit_code: "under a chance constraint, the plan leaves robots in each other's way that waits "
    "and detours could not clear (the message names the first); --accept-risk takes the plan",
    WindowError.exit_code: "no plan arrives within a job's window (goals.jobs.window): the message names the goal "
    "and the earliest arrival possible",
    UNREACHABLE_GOALS: "tmpnav replan: the rest is planned and written, but goals no robot can reach any more "
    "(behind a closed door, a window closed, only robots that are down may do them) are left out, one line each",
    130: "interrupted (Ctrl-C)",
    143: "terminated (SIGTERM; a parent process sees it killed by the signal): the processes it started "
    "are stopped and earlier outputs kept, as after Ctrl-C",
}
