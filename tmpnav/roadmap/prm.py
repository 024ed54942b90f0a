"""Stage 3: the probabilistic roadmap, grown by OMPL (the only module that imports ompl).

The roadmap lives in the plane (x, y): the robots are discs, so orientation does not
affect collisions, and headings along a path follow from the controls (turn, then drive).
One roadmap serves the whole team, built for the largest robot radius, as the paper's pose
instantiations are shared by all robots.

Determinism: OMPL's seed is set before any draw, and the PRM grows in the calling thread
(``growRoadmapPtc``) until it holds ``samples`` milestones; a time limit would make the
roadmap depend on the machine's speed.
"""

from __future__ import annotations

import gc
import hashlib
import itertools
import math
import time
from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np

from tmpnav.errors import RoadmapError
from tmpnav.types import Roadmap, RoadmapParams, RobotSpec
from tmpnav.world import World


def sample_instantiations(
    world: World,
    room: str,
    radius: float,
    k: int,
    rng: np.random.Generator,
    allowed: np.ndarray | None = None,
    clearance: float = 0.0,
) -> np.ndarray:
    """k collision-free positions (k, 2) drawn uniformly in a room's free space (only in the
    cells ``allowed`` (rows, cols), if given: a pocket of the room no robot reaches has none),
    and, where the room has any, only where a robot keeps ``clearance`` (m) from the walls."""
    cells = world.free_cells_in_room(room, radius)
    if allowed is not None:
        i, j, _ = world.grid.cells(cells)
        cells = cells[allowed[i, j]]
    if cells.shape[0] == 0:
        raise RoadmapError(f"room {room!r} has no free space a robot of radius {radius:g} m can reach")
    if clearance > 0:
        i, j, _ = world.grid.cells(cells)
        roomy = world.clearance[i, j] >= radius + world.grid.resolution + clearance
        cells = cells[roomy] if roomy.any() else cells
    half = world.grid.resolution / 2.0
    out: list[np.ndarray] = []
    for _ in range(100 * k):
        p = cells[rng.integers(cells.shape[0])] + rng.uniform(-half, half, size=2)
        if world.is_free(p[None, :], radius)[0]:
            out.append(p)
            if len(out) == k:
                break
    return np.array(out)


def reachable_free_space(world: World, radius: float, starts: np.ndarray) -> np.ndarray:
    """Cells (rows, cols) where a robot fits and that connect to some robot's start.

    Sampling only there keeps OMPL's milestones off islands no robot can reach (the
    space behind a building's outer walls, sealed rooms).
    """
    from scipy import ndimage

    free = world.clearance >= radius + world.grid.resolution
    labels, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
    i, j, _ = world.grid.cells(starts)
    keep = np.setdiff1d(np.unique(labels[i, j]), [0])
    return np.isin(labels, keep)


#: directions probed for a passage's axis at its narrowest point (:func:`passage_milestones`)
PASSAGE_DIRECTIONS = 16


def passage_milestones(world: World, radius: float, clearance: float, free_cells: np.ndarray) -> np.ndarray:
    """Milestones through the middle of the map's narrow passages (doors, gaps between racks):
    where a robot cannot keep ``clearance`` from the walls, uniform samples rarely fall in the
    middle, and the few edges through a door graze its frame (a 1.1 m door of a generated
    office was crossed 0.25 m from one frame, a collision bound of 1 at a position std of 6 mm).

    A passage's narrowest point is a saddle of the clearance field on the medial axis of free
    space (Blum's skeleton, scikit-image's ``skeletonize``): a skeleton cell with at least two
    skeleton neighbours, no neighbour narrower, and less than radius + a cell + ``clearance``
    from the walls; a plateau of such cells (a door's depth) gives its middle cell. Its axis is
    the direction in which the clearance at distance d = radius + ``clearance`` + 2 cells is
    largest on both sides; the milestones are the point and the points d along the axis on
    either side (those in ``free_cells``), so the roadmap has an edge along each door's middle.
    Cf. the medial-axis and bridge-test samplers for narrow passages (Wilmarth, Amato and
    Stiller, ICRA 1999; Hsu et al., ICRA 2003). (K, 2) positions; none without ``clearance``."""
    if clearance <= 0:
        return np.zeros((0, 2))
    from scipy import ndimage
    from skimage.morphology import skeletonize

    grid, c = world.grid, world.clearance
    skeleton = skeletonize(free_cells)
    neighbours = ndimage.convolve(skeleton.astype(np.uint8), np.ones((3, 3), np.uint8), mode="constant") - skeleton
    along = ndimage.minimum_filter(np.where(skeleton, c, np.inf), size=3, mode="constant", cval=np.inf)
    narrow = radius + grid.resolution + clearance
    throats = skeleton & (neighbours >= 2) & (c < narrow) & (c <= along)
    labels, n = ndimage.label(throats, structure=np.ones((3, 3), dtype=bool))
    if n == 0:
        return np.zeros((0, 2))
    d = radius + clearance + 2 * grid.resolution
    angles = np.pi * np.arange(PASSAGE_DIRECTIONS) / PASSAGE_DIRECTIONS
    axes = np.column_stack([np.cos(angles), np.sin(angles)])
    x0, y0 = grid.origin

    def clearance_at(points: np.ndarray) -> np.ndarray:
        i, j, inside = grid.cells(points)
        out = np.zeros(len(points))
        out[inside] = np.where(free_cells[i[inside], j[inside]], c[i[inside], j[inside]], 0.0)
        return out

    out: list[np.ndarray] = []
    for k, box in enumerate(ndimage.find_objects(labels), start=1):  # each plateau within its bounding box
        ii, jj = np.nonzero(labels[box] == k)
        ii, jj = ii + box[0].start, jj + box[1].start
        m = int(np.argmin((ii - ii.mean()) ** 2 + (jj - jj.mean()) ** 2))
        p = np.array([x0 + (jj[m] + 0.5) * grid.resolution, y0 + (ii[m] + 0.5) * grid.resolution])
        both = np.minimum(clearance_at(p + d * axes), clearance_at(p - d * axes))
        u = axes[int(np.argmax(both))]
        out.extend(q for q in (p, p + d * u, p - d * u) if clearance_at(q[None, :])[0] > 0)
    return np.array(out).reshape(-1, 2)


def _validity_checker(world: World, free_cells: np.ndarray):
    """A fast scalar validity check for OMPL's callback (the milestones it samples)."""
    free = free_cells.tolist()
    x0, y0 = world.grid.origin
    inv = 1.0 / world.grid.resolution
    rows, cols = world.grid.shape

    def is_valid(state) -> bool:
        i = math.floor((state[1] - y0) * inv)
        j = math.floor((state[0] - x0) * inv)
        return 0 <= i < rows and 0 <= j < cols and free[i][j]

    return is_valid


@nb.njit(cache=True)
def _free_at(x: float, y: float, free: np.ndarray, x0: float, y0: float, inv: float) -> bool:
    """The validity checker's test (:func:`_validity_checker`), compiled."""
    i = math.floor((y - y0) * inv)
    j = math.floor((x - x0) * inv)
    return 0 <= i < free.shape[0] and 0 <= j < free.shape[1] and free[i, j]


@nb.njit(cache=True)
def _segment_free(
    x1: float, y1: float, x2: float, y2: float, nd: int, free: np.ndarray, x0: float, y0: float, inv: float
) -> bool:
    """Whether OMPL's discrete motion validator finds the segment free: the end (x2, y2) and
    the nd - 1 states it interpolates between the ends (``from + (to - from) * (j / nd)``,
    RealVectorStateSpace::interpolate), each as the validity checker tests it. The validator
    visits them in bisection order, stopping at the first invalid one; the answer is the same."""
    if not _free_at(x2, y2, free, x0, y0, inv):
        return False
    for j in range(1, nd):
        t = j / nd
        if not _free_at(x1 + (x2 - x1) * t, y1 + (y2 - y1) * t, free, x0, y0, inv):
            return False
    return True


def _motion_validator(ob: Any, si: Any, space: Any, world: World, free_cells: np.ndarray) -> Any:
    """OMPL's discrete motion validator with its state checks compiled: one Python call per
    edge instead of one per state checked along it (on the 20-room building 1.9 million
    calls grew the roadmap in 0.75 s). The same edges: OMPL still counts the segments
    (``validSegmentCount``), and :func:`_segment_free` checks the states it would."""
    free = np.ascontiguousarray(free_cells, dtype=np.bool_)
    x0, y0 = (float(v) for v in world.grid.origin)
    inv = 1.0 / world.grid.resolution
    count = space.validSegmentCount

    class Edges(ob.MotionValidator):
        def checkMotion(self, s1: Any, s2: Any) -> bool:  # OMPL names it
            return bool(_segment_free(s1[0], s1[1], s2[0], s2[1], count(s1, s2), free, x0, y0, inv))

    return Edges(si)


def plane(ob: Any, world: World) -> Any:
    """OMPL's state space of the roadmap: the plane, bounded by the map's extent."""
    xmin, ymin, xmax, ymax = world.grid.extent
    space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, xmin)
    bounds.setLow(1, ymin)
    bounds.setHigh(0, xmax)
    bounds.setHigh(1, ymax)
    space.setBounds(bounds)
    return space


#: the roadmap grows until every room connects to a robot's start, up to this many times
#: ``roadmap.samples`` milestones (doubling each round) and GROWTH_SECONDS of growing
GROWTH, GROWTH_SECONDS = 32, 120.0


def _grow(
    world: World,
    free_cells: np.ndarray,
    params: RoadmapParams,
    specials: np.ndarray,
    connected: Callable[[np.ndarray, np.ndarray], bool],
) -> tuple[np.ndarray, np.ndarray, int]:
    """Grow the PRM with OMPL and add ``specials`` (instantiations, starts) as milestones, then
    grow it further, doubling its milestones each round, until ``connected(nodes, edges)`` (every
    room reaches a robot's start) or GROWTH times ``params.samples`` milestones (or GROWTH_SECONDS).
    Where the first round's uniform samples did not connect it, each later round puts its first
    half of new milestones on PRM's bounce walks from the milestones that failed to connect
    (OMPL's expansion step, ``expandRoadmapPtc``: a door uniform samples rarely find; a
    generated 24-room office connected at 6,098 milestones, not after four rounds at 24,098) and
    samples the rest uniformly. A roadmap that one round connects is the one uniform samples
    make: walks in its first round changed the plans of the generated offices by -1.4% to +5.4%.

    Returns the vertices (N, 2), the undirected edges (E, 2) and the milestones grown (before
    the specials). A roadmap connected at ``params.samples`` is the one grown to that many."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    ou.RNG.setSeed(params.seed + 1)  # OMPL treats seed 0 as "pick one at random"
    space = plane(ob, world)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(_validity_checker(world, free_cells))
    # check edges every half cell: fine enough for the narrowest door the grid can show
    si.setStateValidityCheckingResolution(0.5 * world.grid.resolution / space.getMaximumExtent())
    validator = _motion_validator(ob, si, space, world, free_cells)
    si.setMotionValidator(validator)
    si.setup()

    pdef = ob.ProblemDefinition(si)
    for x, y in specials[:-1]:
        s = si.allocState()
        s[0], s[1] = float(x), float(y)
        pdef.addStartState(s)
    goal = si.allocState()
    goal[0], goal[1] = float(specials[-1, 0]), float(specials[-1, 1])
    pdef.setGoalState(goal)

    prm = og.PRM(si)
    prm.setMaxNearestNeighbors(params.neighbors)
    prm.setProblemDefinition(pdef)  # PRM needs it before growing (it segfaults otherwise)
    prm.setup()
    milestones = prm.milestoneCount
    target, started = params.samples, time.perf_counter()
    prm.growRoadmapPtc(ob.PlannerTerminationCondition(lambda: milestones() >= target))
    grown = milestones()
    # solve() adds the start and goal states as milestones, connected by PRM's own strategy;
    # the always-true termination condition stops it from growing the roadmap any further
    prm.solve(ob.plannerAlwaysTerminatingCondition())
    nodes, edges = _roadmap_of(ob, si, prm)
    while not connected(nodes, edges) and target < GROWTH * params.samples:
        if time.perf_counter() - started > GROWTH_SECONDS:
            break
        target = min(2 * target, GROWTH * params.samples)
        total = target + len(specials)
        # from the second round on, half of the round's new milestones on PRM's bounce walks from
        # the milestones that failed to connect (OMPL's expansion step: a narrow door), the rest
        # sampled uniformly (the roadmap as dense everywhere as a round of uniform samples makes it)
        if target > 2 * params.samples:  # the first round's uniform samples did not connect it
            half = (milestones() + total) // 2
            prm.expandRoadmapPtc(ob.PlannerTerminationCondition(lambda half=half: milestones() >= half))
        prm.growRoadmapPtc(ob.PlannerTerminationCondition(lambda total=total: milestones() >= total))
        grown = target
        nodes, edges = _roadmap_of(ob, si, prm)
    del prm, pdef, si, space, goal, validator
    gc.collect()  # release the OMPL objects now, not at interpreter exit
    return nodes, edges, grown


def _roadmap_of(ob: Any, si: Any, prm: Any) -> tuple[np.ndarray, np.ndarray]:
    """The PRM's vertices (N, 2) and undirected edges (E, 2), as plain arrays."""
    data = ob.PlannerData(si)
    prm.getPlannerData(data)
    n = data.numVertices()
    nodes = np.empty((n, 2))
    edges: list[tuple[int, int]] = []
    for i in range(n):
        st = data.getVertex(i).getState()
        nodes[i] = st[0], st[1]
        edges.extend((i, j) for j in data.getEdges(i) if i < j)
    del data
    return nodes, np.array(edges, dtype=np.int64).reshape(-1, 2)


def build_roadmap(world: World, robots: tuple[RobotSpec, ...], params: RoadmapParams) -> Roadmap:
    """The roadmap with k pose instantiations per room (one, at the goal pose, for a room whose
    job gives one: ``params.poses``), a node at every robot's start and, with a clearance
    (``params.clearance``), nodes through the middle of every narrow passage
    (:func:`passage_milestones`).

    It grows beyond ``params.samples`` milestones while free space joins two of its special
    milestones (instantiations, starts) that it does not (a door too narrow for uniform
    sampling to find at that size), up to GROWTH times as many. Instantiations that end up in
    no component holding a robot start are dropped; a room left with none is an error naming it.
    """
    radius = max(r.radius for r in robots)
    rng = np.random.default_rng(params.seed)
    starts = np.array([[r.pose.x, r.pose.y] for r in robots])
    free_cells = reachable_free_space(world, radius, starts)
    si_, sj_, _ = world.grid.cells(starts)
    for robot, (x, y), ok in zip(robots, starts, free_cells[si_, sj_], strict=True):
        if not ok:  # OMPL would refuse it as a start state: no milestone there
            raise RoadmapError(
                f"robot {robot.name!r} starts at [{x:g}, {y:g}], closer to a wall or a closed door than the "
                f"roadmap's robot radius and a grid cell ({radius + world.grid.resolution:g} m); expected a start "
                "with that clearance"
            )
    # instantiations only where OMPL may put milestones: one in a pocket of the room cut off by
    # noise in the map would be refused as a start state, and its room would lose it
    given = {room: np.array([[x, y]]) for room, x, y in params.poses}  # a job's goal pose: the one instantiation
    inst = {
        room.name: given[room.name]
        if room.name in given
        else sample_instantiations(
            world, room.name, radius, params.instantiations, rng, free_cells, params.clearance or 0.0
        )
        for room in world.rooms
    }
    passages = passage_milestones(world, radius, params.clearance or 0.0, free_cells)
    specials = np.vstack([*inst.values(), passages, starts])  # the starts last (kept_of)
    sizes = [len(pts) for pts in inst.values()]

    def kept_of(nodes: np.ndarray, edges: np.ndarray) -> list[tuple[int, ...]]:
        """Each room's instantiations (roadmap node indices) in a component holding a robot's start."""
        index = {(float(x), float(y)): i for i, (x, y) in enumerate(nodes)}
        special_ids = np.array([index[(float(x), float(y))] for x, y in specials])
        labels = _components(nodes.shape[0], edges)
        reachable = set(labels[special_ids[-len(robots) :]].tolist())
        bounds = np.cumsum([0, *sizes])
        return [
            tuple(int(i) for i in special_ids[lo:hi] if labels[i] in reachable) for lo, hi in itertools.pairwise(bounds)
        ]

    # the roadmap is complete when every two instantiations or starts that free space joins are in
    # one of its components: each room then reaches every robot that free space lets into it. The
    # passages' milestones only help it get there: one left alone in a pocket of a passage (a
    # generated depot: one of its 2,430, at 0.30 m from the racks) grew the roadmap to 16 times
    # its milestones, 8 s, for nothing a room needed
    from scipy import ndimage

    space, _ = ndimage.label(world.clearance >= radius + world.grid.resolution, structure=np.ones((3, 3), dtype=bool))
    needed = np.vstack([*inst.values(), starts])
    si, sj, _ = world.grid.cells(needed)
    joined = space[si, sj]

    def complete(nodes: np.ndarray, edges: np.ndarray) -> bool:
        index = {(float(x), float(y)): i for i, (x, y) in enumerate(nodes)}
        labels = _components(nodes.shape[0], edges)[[index[(float(x), float(y))] for x, y in needed]]
        return all(len(set(labels[joined == g].tolist())) == 1 for g in np.unique(joined))

    nodes, edges, grown = _grow(world, free_cells, params, specials, complete)
    kept = kept_of(nodes, edges)
    instantiations: dict[str, tuple[int, ...]] = {}
    for (name, pts), ids in zip(inst.items(), kept, strict=True):
        if not ids:
            raise RoadmapError(
                f"room {name!r}: none of its {len(pts)} pose instantiations connects to a robot's start "
                f"through the roadmap, grown to {grown} milestones (from roadmap.samples {params.samples}): "
                "the passage to it is narrower than a robot, or too narrow to find; widen it, or raise "
                "roadmap.samples or roadmap.neighbors"
            )
        instantiations[name] = ids
    index = {(float(x), float(y)): i for i, (x, y) in enumerate(nodes)}
    start_ids = [index[(float(x), float(y))] for x, y in starts]
    weights = np.linalg.norm(nodes[edges[:, 0]] - nodes[edges[:, 1]], axis=1)
    digest = hashlib.sha256(
        nodes.tobytes() + edges.tobytes() + repr(sorted(instantiations.items())).encode()
    ).hexdigest()
    return Roadmap(
        nodes=nodes,
        edges=edges,
        weights=weights,
        instantiations=instantiations,
        starts={r.name: int(i) for r, i in zip(robots, start_ids, strict=True)},
        fingerprint=digest,
    )


def with_starts(base: Roadmap, world: World, robots: tuple[RobotSpec, ...], params: RoadmapParams) -> Roadmap | None:
    """``base`` (grown by :func:`build_roadmap` for this world and ``params``) with a node at each
    robot's start: a replan's roadmap, its robots where they are now.

    A start joins the ``params.neighbors`` milestones nearest to it that a straight drive reaches
    (the segment checked as OMPL's motion validator checks an edge), as PRM joins a milestone;
    its edges lead out only (``Roadmap.sources``), so every path between the base's nodes, and
    every motion from them, stays as it was. A start on a node of ``base`` is that node. None
    when a start joins no milestone (the caller grows a roadmap of its own)."""
    if base.sources:
        raise ValueError("with_starts: the base roadmap already has sources")
    radius = max(r.radius for r in robots)
    positions = np.array([[r.pose.x, r.pose.y] for r in robots])
    free = np.ascontiguousarray(reachable_free_space(world, radius, positions), dtype=np.bool_)
    x0, y0 = (float(v) for v in world.grid.origin)
    inv = 1.0 / world.grid.resolution
    longest = 0.5 * world.grid.resolution  # the validity checking resolution of _grow
    index = {(float(x), float(y)): i for i, (x, y) in enumerate(base.nodes)}
    nodes, edges, sources = [base.nodes], [base.edges], []
    starts: dict[str, int] = {}
    added: dict[tuple[float, float], int] = {}
    for robot, (x, y) in zip(robots, positions, strict=True):
        key = (float(x), float(y))
        if key in index or key in added:
            starts[robot.name] = index.get(key, added.get(key, -1))
            continue
        if not bool(world.is_free(np.array([key]), robot.radius)[0]):  # the robot fits where it stands
            return None
        d = np.hypot(base.nodes[:, 0] - x, base.nodes[:, 1] - y)
        near = np.argsort(d, kind="stable")[: params.neighbors]
        joined = []
        for j in near:
            bx, by = (float(v) for v in base.nodes[j])
            if _segment_free(key[0], key[1], bx, by, max(1, math.ceil(d[j] / longest)), free, x0, y0, inv):
                joined.append(int(j))
        if not joined:
            return None
        node = base.n_nodes + len(added)
        added[key] = starts[robot.name] = node
        sources.append(node)
        nodes.append(np.array([key]))
        edges.append(np.array([[node, j] for j in joined], dtype=np.int64))
    all_nodes, all_edges = np.vstack(nodes), np.vstack(edges)
    weights = np.linalg.norm(all_nodes[all_edges[:, 0]] - all_nodes[all_edges[:, 1]], axis=1)
    weights[: base.edges.shape[0]] = base.weights
    digest = hashlib.sha256(
        base.fingerprint.encode() + all_nodes[base.n_nodes :].tobytes() + all_edges[base.edges.shape[0] :].tobytes()
    )
    digest.update(repr(sorted(starts.items())).encode())
    return Roadmap(
        nodes=all_nodes,
        edges=all_edges,
        weights=weights,
        instantiations=dict(base.instantiations),
        starts=starts,
        fingerprint=digest.hexdigest(),
        sources=tuple(sources),
        base=base.fingerprint,
    )


def _components(n: int, edges: np.ndarray) -> np.ndarray:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    return labels
