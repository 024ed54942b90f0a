"""The task planner's answers, remembered: an unchanged task problem is not solved twice.

ENHSP is deterministic: the same PDDL problem and the same engine give the same plan. The
problem is a function of the cost table, the goals, the encoding and its parameters, the
scenario's name and tmpnav's task code, so a run whose inputs are identical to an earlier
one (a warm re-plan, a CI regression run, ``tmpnav simulate`` after ``tmpnav plan``) reads
the earlier plan instead of starting the JVM again.

The key is the SHA-256 of all of those, the PDDL domain files, and the versions of
unified-planning and up-enhsp; the planner's time limit is not part of it, since only
solved plans are stored. The entry lives in the cost database of the cache directory
(:mod:`tmpnav.cachedir`: atomic writes, checksums, no pickle) and holds the plan as action
names with parameters plus the decoded steps. Entries are checked on the way back in: a
step that is not in the cost table, or an entry of the wrong shape, counts as a miss and
the planner runs.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass
from functools import lru_cache
from importlib import metadata
from importlib.resources import files
from typing import Protocol

from tmpnav.digest import source_digest
from tmpnav.results import JSON
from tmpnav.task.encodings import ENCODINGS
from tmpnav.types import CostTable, Goals, MoveKey, PlanStatus

#: task-layer modules whose code decides the PDDL problem or the decoded plan
CODE_FILES = (
    "task/encodings.py",
    "task/encode.py",
    "task/solve.py",
    "task/decode.py",
    "task/memo.py",
    "task/stage.py",
    "task/schedules.py",
)
VERSION = "plan/1"

Action = tuple[str, tuple[str, ...]]  # (action name, parameters)


class EntryStore(Protocol):
    """Where entries are remembered: the cost database (``tmpnav.oracle.cache.DiskCache``)."""

    def get_many(self, keys: Iterable[str]) -> dict[str, object]: ...

    def put_many(self, items: dict[str, object]) -> None: ...


@dataclass(frozen=True)
class Memo:
    """A solved task problem, as remembered."""

    status: PlanStatus
    engine: str
    actions: tuple[Action, ...]  # in the planner's order
    steps: tuple[tuple[MoveKey, ...], ...]  # the decoded steps, same order
    sizes: tuple[int, int, int]  # the problem's actions, pair actions, reshaped rooms


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
    return str(h.hexdigest())


def table_digest(table: CostTable) -> str:
    """A digest of the cost table's content (floats by ``repr``, which round-trips)."""
    parts = (
        table.robots,
        table.rooms,
        table.locations,
        sorted(table.start_location.items()),
        sorted((k, repr(v)) for k, v in table.single.items()),
        sorted((k, repr(v)) for k, v in table.pair.items()),
        sorted((k, repr(v)) for k, v in table.duration.items()),
        sorted((k, repr(v)) for k, v in table.pair_duration.items()),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def memo_key(
    table: CostTable, goals: Goals, encoding: str, min_gain: float, planner: str, name: str, span_weight: float = 0.0
) -> str:
    """The key of the task problem these inputs make, with the engine that solves it."""
    parts = (VERSION, _code_version(), table_digest(table), goals, encoding, repr(min_gain), planner, name)
    return hashlib.sha256(repr((*parts, repr(span_weight))).encode()).hexdigest()


def memo_to_entry(memo: Memo) -> JSON:
    """The JSON entry stored for a memo."""
    actions, pair_actions, reshaped = memo.sizes
    return {
        "status": memo.status.value,
        "engine": memo.engine,
        "actions": [[name, list(params)] for name, params in memo.actions],
        "steps": [[list(m) for m in step] for step in memo.steps],
        "task": {"actions": actions, "pair_actions": pair_actions, "reshaped_rooms": reshaped},
    }


def entry_to_memo(entry: object, table: CostTable) -> Memo | None:
    """The remembered plan, or None when the entry is malformed or does not fit this cost table."""
    if not isinstance(entry, dict):
        return None
    try:
        steps = tuple(tuple((str(m[0]), str(m[1]), str(m[2])) for m in step) for step in entry["steps"])
        actions = tuple((str(name), tuple(str(p) for p in params)) for name, params in entry["actions"])
        task = entry["task"]
        memo = Memo(
            status=PlanStatus(entry["status"]),
            engine=str(entry["engine"]),
            actions=actions,
            steps=steps,
            sizes=(int(task["actions"]), int(task["pair_actions"]), int(task["reshaped_rooms"])),
        )
    except (KeyError, TypeError, ValueError, IndexError):
        return None
    return memo if _fits(memo, table) else None


def _fits(memo: Memo, table: CostTable) -> bool:
    """Every step is a move (or a pair of moves) of the cost table, one per action."""
    for step in memo.steps:
        if len(step) == 1 and step[0] not in table.single:
            return False
        if len(step) == 2 and step not in table.pair and (step[1], step[0]) not in table.pair:
            return False
        if len(step) not in (1, 2):
            return False
    return len(memo.actions) == len(memo.steps)
