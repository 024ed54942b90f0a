"""Motion floors: the least any move can cost, whatever beliefs it starts from or shares.

A move's cost is c = M_u c_u + M_G c_G + M_Sigma c_Sigma, and c_G and c_Sigma are never
negative, so c >= M_u c_u. The control usage c_u of a roadmap path is at least that of its
driving steps: an edge of length l is driven in n = ceil(l / (v dt)) steps at l / (n dt), so
it adds l^2 / (n dt) >= l^2 / (l / v + dt); turning on the spot only adds. Hence every move
of robot r from location o to room t costs at least

    M_u min over s in nodes(o), g in instantiations(t) of sum over the edges e of the path s -> g of
        l_e^2 / (l_e / v_r + dt),

the minimum over every roadmap path (Dijkstra with these edge weights), where nodes(o) are
o's pose instantiations, or the robot's start node for its start location. This holds in
every context -- canonical or carried beliefs, alone or in a paired move, whichever pose
instantiation the robot stands on -- so a lower bound computed from these floors
(:func:`tmpnav.task.bound.lower_bound`) bounds every plan, including those with paired moves
that were never simulated. It is weak where uncertainty dominates the cost: it only counts
driving.

The same paths give each move's time floor, the shortest path at the robot's speed, from
which :func:`tmpnav.task.bound.makespan_bound` bounds the makespan of every schedule.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from tmpnav.types import CostTable, Goals, MoveKey, Roadmap, Scenario


def motion_floors(scenario: Scenario, roadmap: Roadmap, start_location: dict[str, str], goals: Goals) -> CostTable:
    """A cost table of the goal rooms whose every single move costs its motion floor (no pairs),
    and takes its time floor (``duration``): the shortest roadmap path at the robot's speed,
    which no move beats however it turns (a move drives each edge of length l in
    ceil(l / (v dt)) >= l / (v dt) steps, and turning on the spot only adds)."""
    dt = scenario.models.dt
    driving = _floors(scenario, roadmap, start_location, goals, lambda length, v: length**2 / (length / v + dt))
    single = {m: scenario.cost.M_u * f for m, f in driving.items()}
    times = _floors(scenario, roadmap, start_location, goals, lambda length, v: length / v)
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    locations = tuple(dict.fromkeys([*rooms, *start_location.values()]))
    duration = {m: t for m, t in times.items() if m in single}
    names = tuple(r.name for r in scenario.robots)
    return CostTable(names, rooms, locations, dict(start_location), single, {}, duration)


def _floors(
    scenario: Scenario,
    roadmap: Roadmap,
    start_location: dict[str, str],
    goals: Goals,
    weight: Callable[[np.ndarray, float], np.ndarray],
) -> dict[MoveKey, float]:
    """The least sum of ``weight(edge length, speed)`` over the roadmap paths of every move."""
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    single: dict[MoveKey, float] = {}
    for speed in sorted({r.speed for r in scenario.robots}):
        robots = [r.name for r in scenario.robots if r.speed == speed]
        dist = _distances(roadmap, weight(roadmap.weights, speed))
        for r in robots:
            origins = {start_location[r]: (roadmap.starts[r],), **{x: roadmap.instantiations[x] for x in rooms}}
            for o, nodes in origins.items():
                reach = dist(nodes)
                for t in rooms:
                    if t == o or t == start_location[r]:
                        continue
                    floor = float(reach[:, list(roadmap.instantiations[t])].min())
                    if np.isfinite(floor):
                        single[(r, o, t)] = floor
    return single


def _distances(roadmap: Roadmap, weights: np.ndarray) -> Callable[[tuple[int, ...]], np.ndarray]:
    """Shortest paths with the given edge weights, from given source nodes."""
    w = np.maximum(weights, 1e-12)  # csgraph drops explicit zeros (a 1e-12 excess is below the bound's rounding)
    n = roadmap.n_nodes
    rows = np.concatenate([roadmap.edges[:, 0], roadmap.edges[:, 1]])
    cols = np.concatenate([roadmap.edges[:, 1], roadmap.edges[:, 0]])
    graph = csr_matrix((np.concatenate([w, w]), (rows, cols)), shape=(n, n))
    memo: dict[tuple[int, ...], np.ndarray] = {}

    def from_nodes(nodes: tuple[int, ...]) -> np.ndarray:
        if nodes not in memo:
            memo[nodes] = np.atleast_2d(dijkstra(graph, directed=False, indices=list(nodes)))
        return memo[nodes]

    return from_nodes
