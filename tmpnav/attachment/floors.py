"""Motion floors: the least a move can cost and take, whatever beliefs it starts from or shares.

A move's cost is c = M_u c_u + M_G c_G + M_Sigma c_Sigma, and c_G and c_Sigma are never
negative. **The path is known.** A move of robot r from a node s (where it stands: its start
node, or a pose instantiation of its origin room) towards an instantiation g of room t drives
the roadmap's shortest path s -> g (the motion library's :class:`RoadmapGraph`, under a
chance constraint with its safe weights), turn-then-drive (:func:`path_controls`): before
each edge with a length l it turns on the spot by the angle phi between its heading and the
edge, in n = ceil(phi / (omega_max dt)) steps at phi / (n dt), then drives l in
n = ceil(l / (v dt)) steps at l / (n dt). A stretch of amount a (metres or radians) covered
in n steps adds n dt seconds and a^2 / (n dt) to c_u = sum (v^2 + omega^2) dt. So, along the
path, every step count and every addition to c_u is known, but for the first turn, which
depends on the heading the robot starts with: its start pose's on its first move; with
carried beliefs (``arrived``), on a room's node, the heading of one of the edges into that
node, the last edge it drove (a path arrives by an edge with a length; where an edge into
the node has none, any heading); with the canonical states of table costs, any heading (the
first turn counted as 0). The floor of the move is the least over s in nodes(o), g in
instantiations(t) and the possible start headings of

    (M_u + M_Sigma kappa) c_u,drive(s -> g) + M_u c_u,turn(s -> g),

and its time floor the least of the path's seconds, computed in one walk of each shortest-path
tree (:func:`_walk`; tests/attachment/test_floors.py checks it against path_controls). A
paired move drives each robot's own path (its partner waits at the end), so both floors hold
for each robot of a pair too; in every context -- canonical or carried beliefs, alone or
paired, whichever instantiation the oracle picks -- and a lower bound computed from them
(:func:`tmpnav.task.bound.lower_bound`, :func:`tmpnav.task.bound.makespan_bound`) bounds
every plan tmpnav can plan on this roadmap, including those with paired moves never
simulated. A plan kept apart afterwards (tmpnav.attachment.conflicts) may drive a detour:
the bound is the plan's as planned. Step counts and lengths are taken with a slack of
:data:`SLACK` on the floor's side, for the rounding of the nominal poses.

**The uncertainty term.** c_Sigma = sum over the move's steps t of trace(Sigma_t) dt, and
trace(Sigma_t) >= Sigma_t[theta, theta], the heading variance after step t's updates. That
variance is at least the heading noise of step t itself, as little as the step's own
bearing measurements can shrink it:

    Sigma_t[theta, theta] >= rho_t / (1 + rho_t I),   rho_t = dt^2 (alpha3 v_t^2 + alpha4 omega_t^2),

with I = L / sigma_b,lm^2 + (n - 1) / sigma_b,mu^2 + B (range tan(max_incidence))^2 / sigma_r^2
(L landmarks, n robots, a range scan of B beams; without mutual observations or a range
sensor that term is 0), **whatever the belief at the start of the move and
whatever the partners do**. Proof (docs/planning.md, "The uncertainty floor"): the EKF's
covariance after step t is the covariance, given the measurements, of the linear-Gaussian
model with the Jacobians it used (F, V at the mean, H at the mean after the previous
update; Joseph form with the optimal gain is exact conditioning), whatever those Jacobians
are. In that model the heading noise b of step t (variance rho_t) is independent of the
prior, of every earlier noise and of the other robots' noise; the positions after step t
do not depend on it (eq. (4) moves the position with the heading before the step), and it
enters a measurement only through the bearing rows of the robot's own measurements (a
landmark's, or of a partner it sees), each with coefficient -1, of noise variance
sigma_b^2 (Q is diagonal), and through the beams of its range scan, each with coefficient
-r tan(beta), at most range tan(max_incidence) in size, of noise variance sigma_range^2;
landmark range rows and a partner's view of the robot have no heading entry. Conditioning
on everything but b can only lower a Gaussian's variance, and leaves 1 / (1/rho_t + sum of
h_theta^2 / sigma^2 over those rows) <= the variance of theta_t. Per step there are at most
L landmark updates, n - 1 mutual ones and one scan.

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

Before this floor counted the paths' turns and step counts, it was the least
driving over every roadmap path, l^2 / (l / v + dt) per edge: the gap of the 20-room
building's plan was 49.7% with it and is 32.0% with this one (docs/planning.md).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from functools import partial

import numba as nb
import numpy as np

from tmpnav.belief.controls import LENGTH_EPS
from tmpnav.oracle.motions import RPP
from tmpnav.roadmap.graph import RoadmapGraph
from tmpnav.types import CostTable, Goals, Models, MoveKey, Roadmap, RobotSpec, Scenario


class FloorsStopped(Exception):
    """:func:`motion_floors` stopped before every floor was computed (its ``stop``)."""


def motion_floors(
    scenario: Scenario,
    paths: RoadmapGraph,
    start_location: dict[str, str],
    goals: Goals,
    arrived: bool = False,
    stop: Callable[[], bool] | None = None,
) -> CostTable:
    """A cost table of the goal rooms whose every single move costs its motion floor (no pairs),
    and takes its time floor (``duration``): the least that driving the path tmpnav drives from a
    node of the origin to a pose instantiation of the target (``paths``' shortest path) costs
    and takes (the module docstring). ``arrived``: a move from a room starts with the heading of
    an edge into its node, as a robot that drove there has (carried beliefs); else with any
    heading (the canonical states of table costs). A robot whose end is its start also has the
    time floor (no cost) of each move back into its start: the makespan's bound counts the way
    back to its dock. ``stop`` is asked between the origins' rows: when it says so,
    :class:`FloorsStopped` is raised."""
    dt, w = scenario.models.dt, scenario.cost
    n, lms, models = len(scenario.robots), len(scenario.landmarks), scenario.models
    roadmap = paths.roadmap
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    inst = roadmap.instantiations
    single: dict[MoveKey, float] = {}
    duration: dict[MoveKey, float] = {}
    paths.prepare(sorted({*(roadmap.starts[r.name] for r in scenario.robots), *(g for x in rooms for g in inst[x])}))
    targets = np.array([g for x in rooms for g in inst[x]], dtype=np.int64)
    room_of = np.array([k for k, x in enumerate(rooms) for _ in inst[x]], dtype=np.int64)
    # the headings a robot can arrive with, by node, and the walks, by (speed, turn rate): the
    # same for every robot that shares them
    arrivals = {g: _arrivals(roadmap, g) if arrived else None for x in rooms for g in inst[x]}
    walked: dict[tuple[float, float], _Walks] = {}
    for spec in scenario.robots:
        walks = walked.setdefault((spec.speed, spec.turn_rate), _Walks(paths, spec, dt, models.driving == "rpp"))
        m_drive = w.M_u + w.M_Sigma * sigma_rate(models, spec.speed, n, lms)
        start = start_location[spec.name]
        origins = _origins(spec, start, roadmap, rooms, arrivals)
        home = goals.end_of(spec.name) == start  # it must come back to where it starts
        for o, nodes in origins.items():
            if stop is not None and stop():
                raise FloorsStopped(f"{len(single)} of the single moves' floors computed")
            # the same for every robot that shares its walks, and for every replan of the roadmap
            tag = ("floors", models.driving, spec.speed, spec.turn_rate, dt, m_drive, w.M_u, nodes, rooms)
            cost, seconds = paths.memo(
                tag,
                tuple(n for n, _ in nodes),
                partial(_row, walks, nodes, targets, room_of, len(rooms), m_drive, w.M_u),
            )
            for k, t in enumerate(rooms):
                if t == o or not np.isfinite(cost[k]):
                    continue
                if t != start:
                    single[(spec.name, o, t)], duration[(spec.name, o, t)] = float(cost[k]), float(seconds[k])
                elif home:  # the way back to a dock it started at: its time only, for the makespan's
                    # floor (the cost bound's rows never enter a robot's start, see tmpnav.task.bound)
                    duration[(spec.name, o, t)] = float(seconds[k])
    locations = tuple(dict.fromkeys([*rooms, *start_location.values()]))
    names = tuple(r.name for r in scenario.robots)
    return CostTable(names, rooms, locations, dict(start_location), single, {}, duration)


def _origins(
    spec: RobotSpec,
    start: str,
    roadmap: Roadmap,
    rooms: tuple[str, ...],
    arrivals: dict[int, tuple[float, ...] | None],
) -> dict[str, tuple[tuple[int, tuple[float, ...] | None], ...]]:
    """Where a robot's moves start, by location: its start node with its heading, and each goal
    room's pose instantiations with the headings it can arrive with (``arrivals``)."""
    origins: dict[str, tuple[tuple[int, tuple[float, ...] | None], ...]] = {
        start: ((roadmap.starts[spec.name], (spec.pose.theta,)),)
    }
    for x in rooms:
        if x != start:
            origins[x] = tuple((g, arrivals[g]) for g in roadmap.instantiations[x])
    return origins


def _row(
    walks: _Walks,
    nodes: tuple[tuple[int, tuple[float, ...] | None], ...],
    targets: np.ndarray,
    room_of: np.ndarray,
    rooms: int,
    m_drive: float,
    m_turn: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The cost and time floors from an origin's ``nodes`` (each with the headings a robot may
    stand there with) to each room: the least over the origin's nodes and the room's
    instantiations (``targets``, of room ``room_of``, one of ``rooms``)."""
    cost, seconds = np.full(rooms, np.inf), np.full(rooms, np.inf)
    for node, headings in nodes:
        c, t_s = walks.floors(node, headings, targets, m_drive, m_turn)
        np.minimum.at(cost, room_of, c)
        np.minimum.at(seconds, room_of, t_s)
    cost.setflags(write=False)
    seconds.setflags(write=False)
    return cost, seconds


def bearing_information(models: Models, landmarks: int, partners: int) -> float:
    """I: the most information on its heading a robot's own bearings can give in one step,
    with ``landmarks`` landmarks and ``partners`` other robots in view, and its range scan's
    beams (rad^-2)."""
    mutual = partners / models.mutual_sensor.sigma_bearing**2 if models.partners_fused else 0.0
    return landmarks / models.landmark_sensor.sigma_bearing**2 + mutual + scan_heading_information(models)


def scan_heading_information(models: Models) -> float:
    """The most information on its heading one range scan can give (rad^-2): a beam's heading
    entry is -r tan(beta) (tmpnav.world.lidar), at most range tan(max_incidence) in size, and a
    scan has ``beams`` of them, each of noise sigma_range; 0 without a range sensor."""
    s = models.range_sensor
    if s is None:
        return 0.0
    return s.beams * (s.range * math.tan(s.max_incidence)) ** 2 / s.sigma_range**2


def heading_floor(models: Models, v: np.ndarray, omega: np.ndarray, information: float) -> np.ndarray:
    """The least heading variance after a step of controls (v, omega), whatever came before
    (the module docstring): rho / (1 + rho I), rho the step's own heading noise (rad^2)."""
    _, _, a3, a4 = models.belief_noise
    rho = models.dt**2 * (a3 * np.square(v) + a4 * np.square(omega))
    return np.asarray(rho / (1.0 + rho * information))


def sigma_rate(models: Models, speed: float, robots: int, landmarks: int) -> float:
    """kappa: c_Sigma >= kappa c_u,drive for every move of a robot driving at most ``speed``,
    among ``robots`` robots and ``landmarks`` landmarks (the module docstring)."""
    _, _, a3, _ = models.belief_noise
    rho_max = models.dt**2 * a3 * speed**2
    information = bearing_information(models, landmarks, robots - 1)
    return models.dt**2 * a3 / (1.0 + rho_max * information)


#: the slack of the floors' step counts: a driven length or a turn is measured from the robot's
#: nominal pose, which is a roadmap node up to rounding (1e-12 m); a step count of a length
#: within this of a multiple of one step's reach is taken both ways, on the floor's side
SLACK = 1e-6


def _seconds(amount: np.ndarray | float, rate: float, dt: float) -> np.ndarray:
    """The least time turn-then-drive can take for a length (m) or a turn (rad) of ``amount``
    at most ``rate`` per second: ceil(amount / (rate dt)) steps of dt, none for nothing."""
    a = np.maximum(np.asarray(amount, dtype=float) - SLACK, 0.0)
    return np.asarray(dt * np.where(a > 0.0, np.ceil(a / (rate * dt)), 0.0))


def _usage(amount: np.ndarray | float, rate: float, dt: float) -> np.ndarray:
    """The least control usage of a length (m) or a turn (rad) of ``amount``: covered in n
    steps at amount / (n dt), it adds amount^2 / (n dt), and n is at most
    ceil(amount / (rate dt)) (the module docstring)."""
    a = np.asarray(amount, dtype=float)
    low = np.maximum(a - SLACK, 0.0)
    most = np.maximum(np.ceil((a + SLACK) / (rate * dt)), 1.0)
    return np.asarray(np.square(low) / (most * dt))


def _arrivals(roadmap: Roadmap, node: int) -> tuple[float, ...] | None:
    """The headings a robot can have on ``node`` after driving there: those of the edges into
    it; None (any heading) where an edge into it has no length."""
    e = roadmap.edges
    neighbours = np.concatenate([e[e[:, 1] == node, 0], e[e[:, 0] == node, 1]])
    delta = roadmap.nodes[node, :2] - roadmap.nodes[neighbours, :2]
    if not neighbours.size or (np.hypot(delta[:, 0], delta[:, 1]) < LENGTH_EPS).any():
        return None
    return tuple(float(h) for h in np.arctan2(delta[:, 1], delta[:, 0]))


class _Walks:
    """What driving the shortest path from a source node to every node takes, for one robot:
    its drives and its turns after the first (:func:`_walk`), and the heading of its first
    edge, so that the first turn is added for the heading the robot starts with."""

    def __init__(self, paths: RoadmapGraph, spec: RobotSpec, dt: float, rpp: bool = False):
        self.paths, self.spec, self.dt, self.rpp = paths, spec, dt, rpp
        self.xy = np.ascontiguousarray(paths.roadmap.nodes[:, :2], dtype=float)

    def _of(self, source: int, targets: np.ndarray) -> np.ndarray:
        """The walk's (5, T) rows at ``targets`` (:func:`_walk`)."""
        s = self.spec
        targets = np.ascontiguousarray(targets, dtype=np.int64)

        def walk() -> np.ndarray:
            dist, pred = self.paths.tree(source)
            return np.asarray(
                _walk(pred, dist, self.xy, source, targets, s.speed, s.turn_rate, self.dt, SLACK, LENGTH_EPS)
            )

        which = hashlib.blake2b(targets.tobytes(), digest_size=16).hexdigest()
        return self.paths.derived(source, ("walk", s.speed, s.turn_rate, self.dt, which), walk)

    def floors(
        self, source: int, headings: tuple[float, ...] | None, targets: np.ndarray, m_drive: float, m_turn: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The cost floor and the time floor of the path from ``source`` to each of ``targets``,
        starting with one of ``headings`` (None: any)."""
        if self.rpp:
            return self._pursued(source, targets, m_drive)
        walked = self._of(source, targets)  # drive c_u, drive s, turn c_u, turn s, first heading
        first = walked[4]
        if headings is None:
            angle = np.zeros_like(first)
        else:
            angle = np.abs(_wrap(first[None, :] - np.asarray(headings)[:, None])).min(axis=0)
        angle = np.where(np.isnan(first), 0.0, angle)
        rate = self.spec.turn_rate
        cost = m_drive * walked[0] + m_turn * (walked[2] + _usage(angle, rate, self.dt))
        seconds = walked[1] + walked[3] + _seconds(angle, rate, self.dt)
        return cost, seconds

    def _pursued(self, source: int, targets: np.ndarray, m_drive: float) -> tuple[np.ndarray, np.ndarray]:
        """The floors of Regulated Pure Pursuit's motions (models.controller: rpp; docs/planning.md,
        "Floors under RPP"). RPP drives a shortened path and cuts its corners, so the roadmap's
        path length bounds nothing: the robot covers at least the straight distance D from the
        source to the target less the goal tolerance, at most at its speed, which gives the time
        floor. Its speed is at least v_lo = min(the regulated minimum speed, its speed, turn_rate
        L / (2 sin(rotate_to_heading_min_angle))) (the last: omega = v 2 sin(a) / L on the arc
        through a carrot at the lookahead L within the rotate angle a) but on the approach to
        the end, within Z = the approach distance plus the longest lookahead of it (the robot is
        within a lookahead of its path); so c_u = sum v^2 dt >= v_lo (D - Z). Turns on the spot
        count 0."""
        p = RPP  # the parameters the planner's motions are driven with
        s = self.spec
        d = np.hypot(*(self.xy[targets] - self.xy[source]).T)
        driven = np.maximum(d - p.xy_goal_tolerance, 0.0)
        shortest = p.min_lookahead_dist if p.use_velocity_scaled_lookahead_dist else p.lookahead_dist
        v_lo = min(
            p.regulated_linear_scaling_min_speed,
            s.speed,
            s.turn_rate * shortest / (2.0 * math.sin(min(p.rotate_to_heading_min_angle, math.pi / 2))),
        )
        steady = np.maximum(driven - (p.approach_velocity_scaling_dist + p.reach), 0.0)
        return m_drive * v_lo * steady, _seconds(driven, s.speed, self.dt)


@nb.njit(cache=True)
def _walk(pred, dist, xy, root, targets, speed, turn_rate, dt, slack, length_eps):
    """Along the shortest-path tree ``pred`` from ``root``, at each of ``targets``: (5, T) rows
    of the drives' c_u and seconds, the turns' c_u and seconds after the first edge with a
    length, and that edge's heading (NaN: none; unreachable targets: inf). Each turn is the one
    turn-then-drive makes: from the heading of the last edge with a length to the next's. Only
    the tree's branches to the targets are walked (a few thousand of a large roadmap's nodes),
    each node once, from the root down."""
    n = pred.shape[0]
    out = np.full((5, n), np.inf)
    last = np.full(n, np.nan)
    done = np.zeros(n, dtype=np.bool_)
    out[0:4, root] = 0.0
    out[4, root] = np.nan
    done[root] = True
    chain = np.empty(n, dtype=np.int64)
    for n0 in targets:
        if done[n0] or not np.isfinite(dist[n0]):
            continue
        k, m = 0, n0
        while not done[m]:
            chain[k] = m
            k += 1
            m = pred[m]
        for j in range(k - 1, -1, -1):
            m = chain[j]
            p = pred[m]
            for r in range(5):
                out[r, m] = out[r, p]
            last[m] = last[p]
            dx, dy = xy[m, 0] - xy[p, 0], xy[m, 1] - xy[p, 1]
            length = math.hypot(dx, dy)
            if length >= length_eps:
                heading = math.atan2(dy, dx)
                if np.isnan(last[p]):
                    out[4, m] = heading
                else:
                    turn = abs((heading - last[p] + math.pi) % (2 * math.pi) - math.pi)
                    out[2, m] += _usage_one(turn, turn_rate, dt, slack)
                    out[3, m] += _seconds_one(turn, turn_rate, dt, slack)
                out[0, m] += _usage_one(length, speed, dt, slack)
                out[1, m] += _seconds_one(length, speed, dt, slack)
                last[m] = heading
            done[m] = True
    result = np.empty((5, targets.shape[0]))
    for i in range(targets.shape[0]):
        for r in range(5):
            result[r, i] = out[r, targets[i]]
    return result


@nb.njit(cache=True)
def _usage_one(amount, rate, dt, slack):
    """:func:`_usage` of one amount."""
    low = max(amount - slack, 0.0)
    return low * low / (max(math.ceil((amount + slack) / (rate * dt)), 1.0) * dt)


@nb.njit(cache=True)
def _seconds_one(amount, rate, dt, slack):
    """:func:`_seconds` of one amount."""
    low = amount - slack
    return dt * math.ceil(low / (rate * dt)) if low > 0.0 else 0.0


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-pi, pi)."""
    return np.asarray((angle + np.pi) % (2 * np.pi) - np.pi)
