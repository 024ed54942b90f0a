"""Run the real ``tmpnav`` command line on fuzzed files, within limits, and check what a
user would see: an exit code tmpnav documents, one line per problem, no traceback.

Every run is a fresh ``python -m tmpnav`` process with its address space capped by
``resource.setrlimit`` (so a runaway allocation becomes a MemoryError, which tmpnav would
report as an internal error, exit 1: a failure here) and a wall-clock limit.
"""

from __future__ import annotations

import json
import math
import os
import re
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from tmpnav.errors import EXIT_CODES

#: address space of one run: tmpnav validating a capped input needs well under 1 GB
VALIDATE_MEMORY = 3 * 2**30
VALIDATE_SECONDS = 60.0
#: plan also runs numba's compiled kernel and ENHSP's JVM (whose heap is capped below)
PLAN_MEMORY = 5 * 2**30
PLAN_SECONDS = 240.0
JAVA_OPTIONS = (
    "-XX:TieredStopAtLevel=1 -XX:+UseSerialGC -Xmx512m -XX:ReservedCodeCacheSize=64m "
    "-XX:CompressedClassSpaceSize=64m -XX:MaxMetaspaceSize=128m"
)

ERROR_LINE = re.compile(r"^error: \S.*$")
#: a one-line warning a run that goes on prints (tmpnav.scenario.advice, robots in each other's way)
WARNING_LINE = re.compile(r"^warning: \S.*$")
#: the anytime search's progress on stderr (tmpnav.cli.options.search_progress): a run's own output
PROGRESS_LINE = re.compile(r"^search +\d+\.\d s  best +\S+(  bound +\S+  gap +\S+%)?  \(.+\)$")


@dataclass(frozen=True)
class Outcome:
    args: tuple[str, ...]
    code: int
    stdout: str
    stderr: str
    seconds: float

    def describe(self) -> str:
        return (
            f"tmpnav {' '.join(self.args)} -> exit {self.code} after {self.seconds:.1f} s\n"
            f"stdout: {self.stdout[-2000:]!r}\nstderr: {self.stderr[-2000:]!r}"
        )


def run_tmpnav(args: list[str], cwd: Path, memory: int, seconds: float) -> Outcome:
    """``python -m tmpnav ARGS`` in ``cwd`` with at most ``memory`` bytes of address space;
    a run past ``seconds`` fails the property (subprocess.TimeoutExpired propagates)."""

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    env = {k: v for k, v in os.environ.items() if not k.startswith("TMPNAV_MAX_")}
    env.update(TMPNAV_JAVA_OPTIONS=JAVA_OPTIONS, PYTHONDONTWRITEBYTECODE="1")
    env.pop("TMPNAV_DEBUG", None)
    start = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=seconds,
        env=env,
        preexec_fn=limit,
    )
    return Outcome(tuple(args), proc.returncode, proc.stdout, proc.stderr, time.monotonic() - start)


def check_reported(outcome: Outcome, allowed: set[int]) -> None:
    """What every run must look like: a documented exit code among ``allowed``, nothing
    but ``error: ...`` and ``warning: ...`` lines (and the search's progress) on stderr, no
    traceback, no internal error."""
    why = outcome.describe()
    assert outcome.code in EXIT_CODES, why
    assert outcome.code in allowed, why
    assert "Traceback" not in outcome.stdout + outcome.stderr, why
    assert "internal error" not in outcome.stderr, why
    lines = outcome.stderr.splitlines()
    assert all(ERROR_LINE.match(line) or WARNING_LINE.match(line) or PROGRESS_LINE.match(line) for line in lines), why
    errors = [line for line in lines if ERROR_LINE.match(line)]
    if outcome.code == 0:
        assert errors == [], why
    else:
        assert errors, why


def check_validate(outcome: Outcome) -> None:
    """``validate``: 0 with one ``ok`` line, or 2 with one line per problem and no ``ok``."""
    check_reported(outcome, {0, 2})
    if outcome.code == 0:
        assert " ok: " in outcome.stdout and outcome.stdout.count("\n") == 1, outcome.describe()
    else:
        assert outcome.stdout == "", outcome.describe()


def check_plan(outcome: Outcome) -> None:
    """``plan`` on a small, solvable world: a plan with finite costs, or bad input (2).
    A timeout (5) is tolerated on a loaded machine; anything else is a bug: an internal
    error (1), a planner failure (3, 7) or "no plan" (6) for goals that are reachable."""
    check_reported(outcome, {0, 2, 5})
    if outcome.code == 0:
        cost = json.loads(outcome.stdout)["cost"]
        assert math.isfinite(cost["planner"]) and math.isfinite(cost["resimulated"]), outcome.describe()
        assert cost["planner"] >= 0 and cost["resimulated"] >= 0, outcome.describe()
