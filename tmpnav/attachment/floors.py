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

**The uncertainty term.** c_Sigma = sum over the move's steps t of trace(Sigma_t) dt, and
trace(Sigma_t) >= Sigma_t[theta, theta], the heading variance after step t's updates. That
variance is at least the heading noise of step t itself, as little as the step's own
bearing measurements can shrink it:

    Sigma_t[theta, theta] >= rho_t / (1 + rho_t I),   rho_t = dt^2 (alpha3 v_t^2 + alpha4 omega_t^2),

with I = L / sigma_b,lm^2 + (n - 1) / sigma_b,mu^2 (L landmarks, n robots; without mutual
observations the second term is 0), **whatever the belief at the start of the move and
whatever the partners do**. Proof (docs/planning.md, "The uncertainty floor"): the EKF's
covariance after step t is the covariance, given the measurements, of the linear-Gaussian
model with the Jacobians it used (F, V at the mean, H at the mean after the previous
update; Joseph form with the optimal gain is exact conditioning), whatever those Jacobians
are. In that model the heading noise b of step t (variance rho_t) is independent of the
prior, of every earlier noise and of the other robots' noise; the positions after step t
do not depend on it (eq. (4) moves the position with the heading before the step), and it
enters a measurement only through the bearing rows of the robot's own measurements (a
landmark's, or of a partner it sees), each with coefficient -1, of noise variance
sigma_b^2 (Q is diagonal); range rows and a partner's view of the robot have no heading
entry. Conditioning on everything but b can only lower a Gaussian's variance, and leaves
1 / (1/rho_t + sum of 1/sigma_b^2 over those rows) <= the variance of theta_t. Per step
there are at most L landmark updates and n - 1 mutual ones.

On a driving step (omega = 0, v <= v_max) rho_t = dt^2 alpha3 v_t^2 <= rho_max = dt^2 alpha3
v_max^2, and rho / (1 + rho I) >= rho / (1 + rho_max I) (it is concave in rho, 0 at 0), so
summing over the driving steps, and dropping the turning steps,

    c_Sigma >= kappa c_u,drive,   kappa = dt^2 alpha3 / (1 + rho_max I),

and every move costs at least (M_u + M_Sigma kappa) times its driving floor. **It is small**
(building-20: kappa = 7.7e-4, against M_u = 1): no floor that holds for every prior and
every partner can count the uncertainty a robot accumulates step after step, because a
partner (or a landmark) next to the robot's *mean* gives unbounded information on its
position (the bearing Jacobian grows as 1/d), and a known position pins the heading of a
driving robot (the lateral displacement is v dt theta). The gap's uncertainty share is
therefore the bound's, not the plan's; docs/planning.md measures it.

The same paths give each move's time floor, the shortest path at the robot's speed, from
which :func:`tmpnav.task.bound.makespan_bound` bounds the makespan of every schedule.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from tmpnav.types import CostTable, Goals, Models, MoveKey, Roadmap, Scenario


def motion_floors(scenario: Scenario, roadmap: Roadmap, start_location: dict[str, str], goals: Goals) -> CostTable:
    """A cost table of the goal rooms whose every single move costs its motion floor (no pairs),
    and takes its time floor (``duration``): the shortest roadmap path at the robot's speed,
    which no move beats however it turns (a move drives each edge of length l in
    ceil(l / (v dt)) >= l / (v dt) steps, and turning on the spot only adds)."""
    dt = scenario.models.dt
    driving = _floors(scenario, roadmap, start_location, goals, lambda length, v: length**2 / (length / v + dt))
    speed = {r.name: r.speed for r in scenario.robots}
    n, lms, models = len(scenario.robots), len(scenario.landmarks), scenario.models
    weight = {v: scenario.cost.M_u + scenario.cost.M_Sigma * sigma_rate(models, v, n, lms) for v in speed.values()}
    single = {m: weight[speed[m[0]]] * f for m, f in driving.items()}
    times = _floors(scenario, roadmap, start_location, goals, lambda length, v: length / v)
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    locations = tuple(dict.fromkeys([*rooms, *start_location.values()]))
    duration = {m: t for m, t in times.items() if m in single}
    names = tuple(r.name for r in scenario.robots)
    return CostTable(names, rooms, locations, dict(start_location), single, {}, duration)


def bearing_information(models: Models, landmarks: int, partners: int) -> float:
    """I: the most information on its heading a robot's own bearings can give in one step,
    with ``landmarks`` landmarks and ``partners`` other robots in view (rad^-2)."""
    mutual = partners / models.mutual_sensor.sigma_bearing**2 if models.mutual_observations else 0.0
    return landmarks / models.landmark_sensor.sigma_bearing**2 + mutual


def heading_floor(models: Models, v: np.ndarray, omega: np.ndarray, information: float) -> np.ndarray:
    """The least heading variance after a step of controls (v, omega), whatever came before
    (the module docstring): rho / (1 + rho I), rho the step's own heading noise (rad^2)."""
    _, _, a3, a4 = models.motion_noise
    rho = models.dt**2 * (a3 * np.square(v) + a4 * np.square(omega))
    return np.asarray(rho / (1.0 + rho * information))


def sigma_rate(models: Models, speed: float, robots: int, landmarks: int) -> float:
    """kappa: c_Sigma >= kappa c_u,drive for every move of a robot driving at most ``speed``,
    among ``robots`` robots and ``landmarks`` landmarks (the module docstring)."""
    _, _, a3, _ = models.motion_noise
    rho_max = models.dt**2 * a3 * speed**2
    information = bearing_information(models, landmarks, robots - 1)
    return models.dt**2 * a3 / (1.0 + rho_max * information)


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
