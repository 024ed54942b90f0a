"""Cache keys and the JSON form of oracle results.

A key is the SHA-256 of everything a result depends on: the oracle's own code (a hash of
the source files that compute results), the world (grid, rooms, landmarks), the roadmap,
the motion and sensing models, the cost weights, the specs of the robots involved, their
start states (node, heading, belief) and the target rooms. Floats enter through ``repr``,
which round-trips exactly, so two keys are equal only for bit-identical inputs.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path
from typing import Any

from tmpnav.oracle.evaluate import Request
from tmpnav.types import CostTerms, MotionResult, Roadmap, Scenario
from tmpnav.world import World

#: modules whose code determines the oracle's results; editing any of them changes every key
CODE_FILES = (
    "belief/models.py",
    "belief/kernel.py",
    "belief/ekf.py",
    "belief/batch.py",
    "belief/controls.py",
    "belief/propagate.py",
    "oracle/evaluate.py",
    "oracle/motions.py",
    "oracle/keys.py",
    "oracle/table.py",
    "roadmap/graph.py",
    "world/visibility.py",
    "world/grid.py",
    "world/geometry.py",
    "types.py",
)
#: imported by those modules without deciding results: orchestration, or content already
#: covered by the world's fingerprint (tests/oracle/test_keys.py checks the two lists)
NOT_RESULT_CODE = ("oracle/oracle.py", "world/build.py")


def source_digest(files: tuple[str, ...]) -> Any:
    """A SHA-256 over the names and bytes of tmpnav source files (paths relative to the package)."""
    root = Path(__file__).resolve().parent.parent
    h = hashlib.sha256()
    for rel in files:
        h.update(rel.encode())
        h.update((root / rel).read_bytes())
    return h


@lru_cache(maxsize=1)
def code_version() -> str:
    return str(source_digest(CODE_FILES).hexdigest())


def context_digest(scenario: Scenario, world: World, roadmap: Roadmap) -> str:
    """The part of every key shared by all actions of one planning problem."""
    parts = (
        code_version(),
        world.fingerprint,
        roadmap.fingerprint,
        repr(scenario.models),
        repr(scenario.cost),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def request_key(context: str, scenario: Scenario, request: Request) -> str:
    robots = tuple(scenario.robot(r) for r in request.robots)
    specs = tuple((r.name, r.radius, r.speed, r.turn_rate) for r in robots)
    return hashlib.sha256(repr((context, specs, request)).encode()).hexdigest()


def to_json(result: MotionResult | None) -> dict[str, Any]:
    if result is None:
        return {"unreachable": True}
    if result.pruned:
        return {"pruned": True, "cost": result.cost, "robots": list(result.robots)}
    return {
        "cost": result.cost,
        "robots": list(result.robots),
        "goal_nodes": list(result.goal_nodes),
        "paths": [list(p) for p in result.paths],
        "terms": [[t.c_u, t.c_G, t.c_Sigma] for t in result.terms],
        "final_mean": list(result.final_mean),
        "final_cov": [list(r) for r in result.final_cov],
        "mutual_steps": result.mutual_steps,
        "final_headings": list(result.final_headings),
    }


def from_json(data: dict[str, Any]) -> MotionResult | None:
    if data.get("unreachable"):
        return None
    if data.get("pruned"):
        return MotionResult(float(data["cost"]), tuple(data["robots"]), (), (), (), (), (), pruned=True)
    return MotionResult(
        cost=float(data["cost"]),
        robots=tuple(data["robots"]),
        goal_nodes=tuple(int(g) for g in data["goal_nodes"]),
        paths=tuple(tuple(int(n) for n in p) for p in data["paths"]),
        terms=tuple(CostTerms(*map(float, t)) for t in data["terms"]),
        final_mean=tuple(float(v) for v in data["final_mean"]),
        final_cov=tuple(tuple(float(v) for v in row) for row in data["final_cov"]),
        mutual_steps=int(data["mutual_steps"]),
        final_headings=tuple(float(h) for h in data["final_headings"]),
    )
