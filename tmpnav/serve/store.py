"""The service's plans and revisions on disk, written all or nothing (:mod:`tmpnav.atomic`) and
read back when the service starts, so a crash or a restart loses no accepted plan.

One folder per site under the cache directory, one per plan inside it::

    <cache>/serve/<site>-<digest>/plans/p3/
        request.json          the plan's request (its goals)
        rev-0000.json         the first plan (plan.json, docs/plan-json.md)
        rev-0001.json         revision 1 ...
        rev-0001.state.json   ... and the team's state it was planned from

A plan's request and its first plan are one atomic group, as are a revision and its state: a
client is told a plan or a revision is accepted only once its group is on disk.
"""

from __future__ import annotations

import hashlib
import json
import re
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tmpnav.atomic import write_files

_REVISION = re.compile(r"^rev-(\d{4,})\.json$")
_PLAN = re.compile(r"^p(\d+)$")


@dataclass
class StoredPlan:
    """A plan as the store holds it: its request, its latest revision's plan.json in memory and
    every revision on disk (a service revising all day keeps one document per plan in memory)."""

    id: str
    folder: Path
    request: dict[str, Any]
    latest: int = 0
    current: dict[str, Any] = field(default_factory=dict)  # the latest revision's plan.json
    #: updates to this plan are applied one at a time, in the order of their revision numbers
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def document(self, number: int) -> dict[str, Any]:
        """The plan.json of revision ``number`` (0 <= number <= latest)."""
        return self.current if number == self.latest else _read(self.path_of(number))

    def path_of(self, number: int) -> Path:
        return self.folder / revision_name(number)


def revision_name(number: int) -> str:
    return f"rev-{number:04d}.json"


class Store:
    """Every plan of one site, in memory and on disk."""

    def __init__(self, cache_root: Path, site_path: Path):
        digest = hashlib.sha256(site_path.read_bytes()).hexdigest()[:12]
        self.root = cache_root / "serve" / f"{site_path.stem}-{digest}" / "plans"
        self.plans: dict[str, StoredPlan] = {}
        self._ids = threading.Lock()
        self._reload()

    def _reload(self) -> None:
        if not self.root.is_dir():
            return
        for folder in sorted(self.root.iterdir(), key=lambda p: _number(p.name)):
            if not _PLAN.match(folder.name) or not (folder / "request.json").is_file():
                continue
            numbers = sorted(int(m.group(1)) for p in folder.iterdir() if (m := _REVISION.match(p.name)))
            # revisions are numbered without gaps; a gap would mean a file removed by hand
            numbers = [n for i, n in enumerate(numbers) if n == i]
            if not numbers:
                continue
            latest = numbers[-1]
            plan = StoredPlan(folder.name, folder, _read(folder / "request.json"), latest)
            plan.current = _read(folder / revision_name(latest))
            self.plans[plan.id] = plan

    def new_id(self) -> str:
        """A plan id not used before in this store (``p1``, ``p2``, ...)."""
        with self._ids:
            taken = [_number(p) for p in self.plans]
            if self.root.is_dir():
                taken += [_number(p.name) for p in self.root.iterdir() if _PLAN.match(p.name)]
            number = max(taken, default=0) + 1
            (self.root / f"p{number}").mkdir(parents=True, exist_ok=False)
            return f"p{number}"

    def add(self, plan_id: str, request: dict[str, Any], first: dict[str, Any]) -> StoredPlan:
        """Store a new plan: its request and its first plan, together."""
        folder = self.root / plan_id
        write_files(folder, {"request.json": _json(request), revision_name(0): _json(first)})
        plan = StoredPlan(plan_id, folder, request, 0, first)
        self.plans[plan_id] = plan
        return plan

    def add_revision(self, plan: StoredPlan, state: Any, revision: dict[str, Any]) -> int:
        """Store the next revision of ``plan`` with the state it was planned from; its number."""
        number = plan.latest + 1
        write_files(plan.folder, {f"rev-{number:04d}.state.json": _json(state), revision_name(number): _json(revision)})
        plan.latest, plan.current = number, revision
        return number

    def drop(self, plan_id: str) -> None:
        """Forget a plan id that never got a plan (its run failed or was cancelled)."""
        folder = self.root / plan_id
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()


def _json(data: Any) -> str:
    return json.dumps(data, separators=(",", ":"), allow_nan=False) + "\n"


def _read(path: Path) -> dict[str, Any]:
    data = json.loads(path.read_text(encoding="utf-8"))
    return data if isinstance(data, dict) else {}


def _number(name: str) -> int:
    m = _PLAN.match(name)
    return int(m.group(1)) if m else 0
