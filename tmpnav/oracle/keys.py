"""Cache keys and the JSON form of oracle results.

A key is the SHA-256 of everything a result depends on: the oracle's own code (a hash of
the source files that compute results), the world (grid, rooms, landmarks), the roadmap,
the motion and sensing models, the cost weights, the specs of the robots involved, their
start states (node, heading, belief) and the target rooms. Floats enter through ``repr``,
which round-trips exactly, so two keys are equal only for bit-identical inputs.
"""

from __future__ import annotations

import hashlib
import struct
from functools import lru_cache
from typing import Any

import numpy as np

from tmpnav.digest import source_digest
from tmpnav.oracle.requests import Request
from tmpnav.oracle.results import pruned_result
from tmpnav.types import CostTerms, MotionResult, Roadmap, Scenario
from tmpnav.world import World

#: modules whose code determines the oracle's results, and only those: editing any of them
#: changes every key. The belief stage's reference (belief/ekf.py, belief/models.py,
#: belief/reference.py) is not among them: it checks the compiled kernel, it does not run.
CODE_FILES = (
    "belief/controls.py",
    "belief/pursuit.py",
    "belief/pursuit_path.py",
    "belief/kernel.py",
    "belief/kernel_bound.py",
    "belief/risk.py",
    "belief/sequences.py",
    "belief/trie.py",
    "oracle/bounds.py",
    "oracle/evaluate.py",
    "oracle/keys.py",
    "oracle/motions.py",
    "oracle/motionsets.py",
    "oracle/nominal.py",
    "oracle/pairs.py",
    "oracle/requests.py",
    "oracle/results.py",
    "oracle/singles.py",
    "oracle/table.py",
    "roadmap/graph.py",
    "roadmap/shortcut.py",
    "types.py",
    "world/geometry.py",
    "world/grid.py",
    "world/lidar.py",
    "world/reach.py",
    "world/scan_information.py",
    "world/visibility.py",
)
#: the modules whose results are cached: their imports, followed through CODE_FILES, are
#: what decides a result (tests/oracle/test_keys.py checks CODE_FILES against them)
RESULT_ENTRY_POINTS = ("oracle/evaluate.py", "oracle/table.py", "oracle/keys.py")
#: imported by those modules without deciding results: orchestration, content already
#: covered by the world's fingerprint, the digest that keys the code itself, and the names of
#: the task's choices that types.py annotates with (tests/oracle/test_keys.py checks the lists)
NOT_RESULT_CODE = ("oracle/oracle.py", "world/build.py", "digest.py", "choices.py")


@lru_cache(maxsize=1)
def code_version() -> str:
    """The digest of :data:`CODE_FILES`: changes whenever code that decides a result does."""
    return str(source_digest(CODE_FILES).hexdigest())


def context_digest(scenario: Scenario, world: World, roadmap: Roadmap) -> str:
    """The part of every key shared by all actions of one planning problem."""
    parts = (
        code_version(),
        world.fingerprint,
        roadmap.grown,  # a replan's starts (Roadmap.sources) enter the keys of the moves from them
        repr(scenario.models),
        repr(scenario.cost),
        repr(scenario.roadmap.clearance),  # the paths the motions drive (tmpnav.roadmap.graph.safe_weights)
        repr([(j.room, j.pose) for j in scenario.goals.jobs if j.pose is not None]),  # headings motions end at
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


#: a start state's bytes in a key: its node, its heading, its mean and its covariance (floats
#: as their IEEE bits: equal bytes for bit-identical inputs only, as ``repr`` gives them)
_START = struct.Struct("<q13d")


def source_bytes(roadmap: Roadmap) -> dict[int, bytes]:
    """Each source node of ``roadmap`` (a replan's start, Roadmap.sources): its position and the
    nodes its edges lead to, as bytes for the keys of the moves from it."""
    out = {}
    for node in roadmap.sources:
        out_edges = roadmap.edges[roadmap.edges[:, 0] == node, 1]
        out[node] = b"source" + roadmap.nodes[node].tobytes() + np.sort(out_edges).astype(np.int64).tobytes()
    return out


def request_key(context: str, scenario: Scenario, request: Request, sources: dict[int, bytes] | None = None) -> str:
    """The key of one request: the context, the specs of its robots and the request itself
    (and for a start at a source node, that node, ``sources`` from :func:`source_bytes`).

    The floats of the start states and the joint covariance enter as their bits: ``repr`` of
    a whole request took 46 us (the 20-room building keyed 7,400 requests in 0.34 s)."""
    robots = tuple(scenario.robot(r) for r in request.robots)
    specs = tuple((r.name, r.radius, r.speed, r.turn_rate) for r in robots)
    head = (context, specs, request.rooms, request.min_gain, request.bound_only, request.max_risk)
    digest = hashlib.sha256(repr(head).encode())
    for start in request.starts:
        digest.update(_START.pack(start.node, start.heading, *start.mean, *(v for row in start.cov for v in row)))
        if sources and start.node in sources:
            digest.update(sources[start.node])
    if request.joint_cov is not None:
        flat = [v for row in request.joint_cov for v in row]
        digest.update(b"joint" + struct.pack(f"<{len(flat)}d", *flat))
    return digest.hexdigest()


def to_json(result: MotionResult | None) -> dict[str, Any]:
    """The JSON form of a result (None: the robots cannot reach their rooms)."""
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
        "steps": list(result.steps),
        "risk": list(result.risk),
    }


def from_json(data: dict[str, Any]) -> MotionResult | None:
    """The result :func:`to_json` wrote."""
    if data.get("unreachable"):
        return None
    if data.get("pruned"):
        return pruned_result(tuple(data["robots"]), float(data["cost"]))
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
        steps=tuple(int(n) for n in data["steps"]),
        risk=tuple(float(p) for p in data.get("risk", ())),
    )
