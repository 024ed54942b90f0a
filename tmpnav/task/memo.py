"""The task planner's answers, remembered: an unchanged task problem is not solved twice.

ENHSP is deterministic: the same PDDL problem and the same engine give the same plan. The
problem is a function of the cost table, the goals, the encoding and its parameters, the
scenario's name and tmpnav's task code, so a run whose inputs are identical to an earlier
one (a warm re-plan, a CI regression run, ``tmpnav simulate`` after ``tmpnav plan``) reads
the earlier plan instead of starting the JVM again.

The key is the SHA-256 of all of those, the PDDL domain files, and the versions of
unified-planning and up-enhsp; the planner's time limit is not part of it, since only
solved plans are stored. The entry lives in the oracle's disk cache (same safety: atomic
writes, checksums, no pickle) and holds the plan as action names with parameters plus the
decoded steps. Entries are checked on the way back in: a step that is not in the cost
table, or an entry of the wrong shape, counts as a miss and the planner runs.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from functools import lru_cache
from importlib import metadata
from importlib.resources import files
from typing import Any

from tmpnav.oracle.keys import source_digest
from tmpnav.task.encode import ENCODINGS
from tmpnav.types import CostTable, Goals, MoveKey, PlanStatus

#: task-layer modules whose code decides the PDDL problem or the decoded plan
CODE_FILES = ("task/encode.py", "task/solve.py", "task/decode.py", "task/memo.py")
VERSION = "plan/1"


@dataclass(frozen=True)
class Memo:
    """A solved task problem, as remembered."""

    status: PlanStatus
    engine: str
    actions: tuple[tuple[str, tuple[str, ...]], ...]  # (action name, parameters), in the planner's order
    steps: tuple[tuple[MoveKey, ...], ...]  # the decoded steps, same order
    task: dict[str, int]  # size of the encoding: actions, pair_actions, reshaped_rooms


@lru_cache(maxsize=1)
def _code_version() -> str:
    h = source_digest(CODE_FILES)
    for name in sorted(e.domain_file for e in ENCODINGS.values()):
        h.update(name.encode())
        h.update(files("tmpnav.pddl").joinpath(name).read_bytes())
    for dist in ("unified-planning", "up-enhsp"):
        try:
            h.update(f"{dist}={metadata.version(dist)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{dist}=absent".encode())
    return h.hexdigest()


def table_digest(table: CostTable) -> str:
    """A digest of the cost table's content (floats by ``repr``, which round-trips)."""
    parts = (
        table.robots,
        table.rooms,
        table.locations,
        sorted(table.start_location.items()),
        sorted((k, repr(v)) for k, v in table.single.items()),
        sorted((k, repr(v)) for k, v in table.pair.items()),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def memo_key(table: CostTable, goals: Goals, encoding: str, min_gain: float, planner: str, name: str) -> str:
    parts = (VERSION, _code_version(), table_digest(table), goals, encoding, repr(min_gain), planner, name)
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def to_json(memo: Memo) -> dict[str, Any]:
    return {
        "status": memo.status.value,
        "engine": memo.engine,
        "actions": [[name, list(params)] for name, params in memo.actions],
        "steps": [[list(m) for m in step] for step in memo.steps],
        "task": dict(memo.task),
    }


def from_json(data: Any, table: CostTable) -> Memo | None:
    """The remembered plan, or None when the entry does not fit this cost table."""
    try:
        steps = tuple(tuple((str(m[0]), str(m[1]), str(m[2])) for m in step) for step in data["steps"])
        actions = tuple((str(name), tuple(str(p) for p in params)) for name, params in data["actions"])
        memo = Memo(
            status=PlanStatus(data["status"]),
            engine=str(data["engine"]),
            actions=actions,
            steps=steps,
            task={str(k): int(v) for k, v in data["task"].items()},
        )
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    for step in memo.steps:
        if len(step) == 1 and step[0] not in table.single:
            return None
        if len(step) == 2 and step not in table.pair and (step[1], step[0]) not in table.pair:
            return None
        if len(step) not in (1, 2):
            return None
    if len(memo.actions) != len(memo.steps):
        return None
    return memo
