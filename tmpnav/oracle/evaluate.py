"""The semantic attachment: the cost of a task action, computed by the motion planner.

For an action (its robots, their start states, their target rooms) the oracle plans each
robot's motion to every pose instantiation of its target room (all combinations for a
pair, two robots never ending on the same pose), propagates the beliefs along the motions
(jointly, with mutual observations, for a pair) and keeps the combination of minimum cost
(paper, section Approach). Its goal nodes are where the robots end up; they start the
robots' next moves.

Two arguments keep the work small without changing any result:

* Factorisation. If the two robots of a combination never see each other and their start
  beliefs are uncorrelated, the joint EKF stays block-diagonal (paper eq. (10)): each
  robot's belief, hence its cost, is the one it has moving alone, because each robot's
  simulated observations come from its own stream. The joint cost is then the sum of two
  single-robot costs, computed once and shared by every pair that contains them.
* Shared prefixes. Motions from one start state follow the shortest-path tree of the
  roadmap, so many simulations begin with identical steps, and the simulated noise of a
  step depends only on the robot's start and the step index. Simulations are run in
  lexicographic order of their controls and each restarts from the state after the steps
  it shares with the previous one (:mod:`tmpnav.belief.kernel`).

A result depends only on its own request, never on the batch it was computed in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tmpnav.belief.kernel import common_prefix_matrix, joint_lex_order, run_sequences
from tmpnav.oracle.motions import MotionLibrary, NominalMotion, stable_seed
from tmpnav.types import CostTerms, CostWeights, MotionResult
from tmpnav.world.visibility import mutual_visibility_sequences


@dataclass(frozen=True)
class StartState:
    """Where and how a robot begins a move: roadmap node, nominal heading, its belief."""

    node: int
    heading: float
    mean: tuple[float, float, float]
    cov: tuple[tuple[float, float, float], ...]


@dataclass(frozen=True)
class Request:
    """One action to evaluate: robots (1 or 2), their start states and target rooms.

    ``joint_cov`` is the full initial covariance (3n x 3n) when the robots' beliefs are
    correlated (carried over from earlier joint moves); None means block-diagonal.
    ``min_gain`` (pairs): when a lower bound proves the pair cannot save this fraction of
    its two single moves, its joint simulations are skipped and the result is marked
    ``pruned`` with the bound as its cost (see :meth:`_Pairs.prune`).
    """

    robots: tuple[str, ...]
    starts: tuple[StartState, ...]
    rooms: tuple[str, ...]
    joint_cov: tuple[tuple[float, ...], ...] | None = None
    min_gain: float | None = None  # a pair that provably saves less is not simulated

    @property
    def n(self) -> int:
        return len(self.robots)

    def mean0(self) -> np.ndarray:
        return np.concatenate([np.array(s.mean) for s in self.starts])

    def cov0(self) -> np.ndarray:
        if self.joint_cov is not None:
            return np.array(self.joint_cov)
        n = self.n
        cov = np.zeros((3 * n, 3 * n))
        for i, s in enumerate(self.starts):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = np.array(s.cov)
        return cov


@dataclass
class EvalStats:
    """Counts for ``tmpnav bench`` and plan.json: what was simulated, what was saved."""

    single_sims: int = 0
    joint_sims: int = 0
    joint_factorized: int = 0
    pairs_pruned: int = 0  # pair requests proved unable to save min_gain (no joint simulation)
    steps_total: int = 0  # EKF steps the simulations span
    steps_computed: int = 0  # EKF steps actually computed (shared prefixes run once)

    def add(self, other: EvalStats) -> None:
        for name in ("single_sims", "joint_sims", "joint_factorized", "pairs_pruned", "steps_total", "steps_computed"):
            setattr(self, name, getattr(self, name) + getattr(other, name))


def mutual_seed(lib: MotionLibrary, robots: tuple[str, ...], starts: tuple[StartState, ...]) -> int:
    """Seed of the simulated mutual observations of robots starting together."""
    return stable_seed(lib.scenario.models.seed, "mutual", robots, tuple(s.node for s in starts))


# --------------------------------------------------------------------------- motions


@dataclass
class MotionSet:
    """The motions of one robot from one start state, in lexicographic order of controls.

    Neighbours in this order share the longest prefixes; ``prefix[a, b]`` is the number of
    leading steps motions a and b have in common.
    """

    robot: str
    start: StartState
    motions: list[NominalMotion]
    by_goal: dict[int, int]
    prefix: np.ndarray
    steps: np.ndarray  # (k,) T of each motion
    c_u: np.ndarray  # (k,) control usage of each motion
    goal_xy: np.ndarray  # (k, 2) nominal final position

    @staticmethod
    def build(robot: str, start: StartState, motions: dict[int, NominalMotion], dt: float) -> MotionSet:
        ordered = sorted(motions.items(), key=lambda kv: tuple(kv[1].controls.ravel().tolist()))
        ms = [m for _, m in ordered]
        T = np.array([m.n_steps for m in ms], dtype=np.int64)
        off = np.concatenate([[0], np.cumsum(T)[:-1]]).astype(np.int64)
        ctrl = np.concatenate([m.controls for m in ms]).reshape(-1, 2)
        prefix = common_prefix_matrix(ctrl, off, T, np.arange(len(ms), dtype=np.int64))
        return MotionSet(
            robot,
            start,
            ms,
            {g: k for k, (g, _) in enumerate(ordered)},
            prefix,
            T,
            np.array([m.c_u(dt) for m in ms]),
            np.array([m.poses[-1, :2] for m in ms]),
        )


def _motion_sets(
    lib: MotionLibrary, wanted: dict[tuple[str, StartState], set[int]]
) -> dict[tuple[str, StartState], MotionSet]:
    sets = {}
    for (robot, start), goals in wanted.items():
        motions = {g: lib.motion(robot, start.node, start.heading, g) for g in sorted(goals)}
        valid = {g: m for g, m in motions.items() if m is not None}
        if valid:
            sets[(robot, start)] = MotionSet.build(robot, start, valid, lib.scenario.models.dt)
    return sets


class MotionTable:
    """Motions laid out for the compiled kernel (concatenated arrays with offsets)."""

    def __init__(self, motions: list[NominalMotion], landmarks: int, dt: float):
        self.offset: dict[int, int] = {}
        self.motions = motions
        self.c_u = np.array([m.c_u(dt) for m in motions])
        self.T = np.array([m.n_steps for m in motions], dtype=np.int64)
        self.off = np.concatenate([[0], np.cumsum(self.T)[:-1]]).astype(np.int64)
        self.ctrl = np.concatenate([m.controls for m in motions]).reshape(-1, 2)
        self.pose = np.concatenate([m.poses for m in motions])
        self.vis = np.ascontiguousarray(np.concatenate([m.lm_visible for m in motions]).reshape(-1, landmarks))
        streams: dict[int, int] = {}
        self.stream = np.array([streams.setdefault(m.noise_seed, len(streams)) for m in motions], dtype=np.int64)
        self.seeds = list(streams)

    @staticmethod
    def of_sets(sets: list[MotionSet], landmarks: int, dt: float) -> MotionTable:
        table = MotionTable([m for ms in sets for m in ms.motions], landmarks, dt)
        k = 0
        for ms in sets:
            table.offset[id(ms)] = k
            k += len(ms.motions)
        return table

    def ids(self, ms: MotionSet, local: np.ndarray) -> np.ndarray:
        return self.offset[id(ms)] + local


def _simulate(
    lib: MotionLibrary,
    table: MotionTable,
    n: int,
    groups: list[tuple[np.ndarray, np.ndarray, int]],
    c_group: np.ndarray,
    c_motion: np.ndarray,
    c_start: np.ndarray,
    c_horizon: np.ndarray,
    c_mvis_off: np.ndarray,
    mvis: np.ndarray,
    mu_noise: np.ndarray | None = None,
    keep_csig: bool = False,
) -> tuple[np.ndarray, ...]:
    """One kernel call: final beliefs, c_Sigma, arrival means and mutual steps per combo,
    the running c_Sigma of every step (when ``keep_csig``), then the history buffers (the
    whole trajectory of the last combo)."""
    models = lib.scenario.models
    landmarks = np.ascontiguousarray(lib.world.landmark_xy)
    L = landmarks.shape[0]
    T_max = int(c_horizon.max(initial=0))
    lm_noise = np.stack([np.random.default_rng(s).standard_normal((T_max + 1, L, 2)) for s in table.seeds])
    if mu_noise is None:
        mu_noise = np.stack([np.random.default_rng(g[2]).standard_normal((T_max + 1, n, n, 2)) for g in groups])
    C = c_group.shape[0]
    out = (
        np.empty((C, 3 * n)),
        np.empty((C, 3 * n, 3 * n)),
        np.empty((C, n)),
        np.empty((C, n, 2)),
        np.empty(C, dtype=np.int64),
        np.zeros((C, T_max + 1, n)) if keep_csig else np.zeros((0, 1, n)),
    )
    Q_lm, Q_mu = models.landmark_sensor.Q, models.mutual_sensor.Q
    h_mean, h_cov = run_sequences(
        n,
        models.dt,
        np.array(models.motion_noise, dtype=float),
        Q_lm,
        np.linalg.cholesky(Q_lm),
        Q_mu,
        np.linalg.cholesky(Q_mu),
        models.observations.value == "max-likelihood",
        landmarks,
        table.off,
        table.T,
        table.ctrl,
        table.pose,
        table.vis,
        table.stream,
        lm_noise,
        np.stack([g[0] for g in groups]),
        np.stack([g[1] for g in groups]),
        np.arange(len(groups), dtype=np.int64),
        mu_noise,
        c_group,
        c_motion,
        c_start,
        c_horizon,
        c_mvis_off,
        mvis,
        *out,
    )
    return (*out, h_mean, h_cov)


@dataclass
class Trajectory:
    """One simulation with its history: ``means`` (T+1, 3n), ``covs`` (T+1, 3n, 3n)."""

    means: np.ndarray
    covs: np.ndarray
    terms: tuple[CostTerms, ...]
    mutual_steps: int


def trajectory(
    lib: MotionLibrary,
    motions: list[NominalMotion],
    mean0: np.ndarray,
    cov0: np.ndarray,
    mvis: np.ndarray,
    mu_noise: np.ndarray,
) -> Trajectory:
    """Simulate n robots through their motions from a joint belief, keeping every step.

    ``mvis`` (h+1, n, n) says who sees whom; ``mu_noise`` (h+1, n, n, 2) are the draws of
    the mutual observations. Used to re-simulate the plan with all robots in one state.
    """
    n = len(motions)
    table = MotionTable(motions, lib.world.landmark_xy.shape[0], lib.scenario.models.dt)
    h = int(table.T.max(initial=0))
    out = _simulate(
        lib,
        table,
        n,
        [(mean0, cov0, 0)],
        np.zeros(1, dtype=np.int64),
        np.arange(n, dtype=np.int64)[None],
        np.zeros(1, dtype=np.int64),
        np.array([h], dtype=np.int64),
        np.zeros(1, dtype=np.int64),
        np.ascontiguousarray(mvis),
        mu_noise[None],
    )
    _, _, csig, fxy, mutual, _, h_mean, h_cov = out
    terms = tuple(
        CostTerms(float(table.c_u[i]), float(np.hypot(*(fxy[0, i] - m.poses[-1, :2]))), float(csig[0, i]))
        for i, m in enumerate(motions)
    )
    return Trajectory(h_mean[: h + 1].copy(), h_cov[: h + 1].copy(), terms, int(mutual[0]))


def _chain(
    P1: np.ndarray, a: np.ndarray, horizon: np.ndarray, P2: np.ndarray | None = None, b: np.ndarray | None = None
) -> np.ndarray:
    """Steps each combo shares with the previous one (0 for the first)."""
    start = np.zeros(a.shape[0], dtype=np.int64)
    if a.shape[0] > 1:
        shared = P1[a[:-1], a[1:]]
        if P2 is not None and b is not None:
            shared = np.minimum(shared, P2[b[:-1], b[1:]])
        start[1:] = np.minimum(shared, horizon[:-1])
    return start


# --------------------------------------------------------------------------- evaluation


def evaluate(lib: MotionLibrary, requests: list[Request]) -> tuple[list[MotionResult | None], EvalStats]:
    """Evaluate actions; None for an action whose robots cannot reach their rooms."""
    stats = EvalStats()
    lib.prepare([s.node for r in requests for s in r.starts])
    wanted: dict[tuple[str, StartState], set[int]] = {}
    for req in requests:
        for robot, start, room in zip(req.robots, req.starts, req.rooms, strict=True):
            wanted.setdefault((robot, start), set()).update(lib.roadmap.instantiations[room])
    sets = _motion_sets(lib, wanted)
    pairs = _Pairs(lib, sets, requests)
    singles = _Singles(lib, sets)
    for req in requests:
        if req.n == 1 and (req.robots[0], req.starts[0]) in sets:
            ms = sets[(req.robots[0], req.starts[0])]
            singles.need(ms, [ms.by_goal[g] for g in lib.roadmap.instantiations[req.rooms[0]] if g in ms.by_goal])
    for ms, local in pairs.singles_needed():
        singles.need(ms, local)
    singles.run(stats)
    pairs.run(stats, singles)
    out: list[MotionResult | None] = []
    for i, req in enumerate(requests):
        out.append(singles.best(req) if req.n == 1 else pairs.best(i, singles))
    return out, stats


class _Singles:
    """Single-robot simulations, one sequence per motion set in trie order."""

    def __init__(self, lib: MotionLibrary, sets: dict):
        self.lib, self.sets = lib, sets
        self.wanted: dict[int, set[int]] = {}
        self.by_id = {id(ms): ms for ms in sets.values()}
        self.results: dict[tuple[int, int], int] = {}

    def need(self, ms: MotionSet, local: list[int] | np.ndarray) -> None:
        self.wanted.setdefault(id(ms), set()).update(int(k) for k in local)

    def run(self, stats: EvalStats) -> None:
        if not self.wanted:
            return
        sets = [self.by_id[k] for k in self.wanted]
        table = MotionTable.of_sets(sets, self.lib.world.landmark_xy.shape[0], self.lib.scenario.models.dt)
        groups, cg, cm, cs, ch = [], [], [], [], []
        for g, ms in enumerate(sets):
            local = np.array(sorted(self.wanted[id(ms)]), dtype=np.int64)
            groups.append((np.array(ms.start.mean), np.array(ms.start.cov), 0))
            horizon = ms.steps[local]
            cg.append(np.full(local.shape[0], g, dtype=np.int64))
            cm.append(table.ids(ms, local))
            cs.append(_chain(ms.prefix, local, horizon))
            ch.append(horizon)
            for k in local:
                self.results[(id(ms), int(k))] = len(self.results)
        c_group, c_motion, c_start, c_horizon = (np.concatenate(x) for x in (cg, cm, cs, ch))
        c_mvis_off = np.concatenate([[0], np.cumsum(c_horizon + 1)[:-1]]).astype(np.int64)
        mvis = np.zeros((int((c_horizon + 1).sum()), 1, 1), dtype=bool)
        self.mean, self.cov, csig, fxy, _, hist, _, _ = _simulate(
            self.lib, table, 1, groups, c_group, c_motion[:, None], c_start, c_horizon, c_mvis_off, mvis, keep_csig=True
        )
        self.csig_hist = hist[:, :, 0]  # running c_Sigma after each step: the bound of pruned pairs
        w = self.lib.scenario.cost
        goal_xy = np.concatenate([self.by_id[id(ms)].goal_xy[sorted(self.wanted[id(ms)])] for ms in sets])
        c_u = np.concatenate([self.by_id[id(ms)].c_u[sorted(self.wanted[id(ms)])] for ms in sets])
        self.c_u, self.c_sigma = c_u, csig[:, 0]
        self.c_g = np.hypot(*(fxy[:, 0] - goal_xy).T)
        self.cost = w.M_u * self.c_u + w.M_G * self.c_g + w.M_Sigma * self.c_sigma
        stats.single_sims += c_group.shape[0]
        stats.steps_total += int(c_horizon.sum())
        stats.steps_computed += int((c_horizon - c_start).sum())

    def index(self, ms: MotionSet, k: int) -> int:
        return self.results[(id(ms), k)]

    def best_cost(self, ms: MotionSet, room: str) -> float:
        """The single-robot optimum of moving to ``room`` (its table cost)."""
        rows = [self.index(ms, ms.by_goal[g]) for g in self.lib.roadmap.instantiations[room] if g in ms.by_goal]
        return float(min(self.cost[r] for r in rows))

    def terms(self, r: int) -> CostTerms:
        return CostTerms(float(self.c_u[r]), float(self.c_g[r]), float(self.c_sigma[r]))

    def best(self, req: Request) -> MotionResult | None:
        key = (req.robots[0], req.starts[0])
        if key not in self.sets:
            return None
        ms = self.sets[key]
        rows = [
            (g, self.index(ms, ms.by_goal[g])) for g in self.lib.roadmap.instantiations[req.rooms[0]] if g in ms.by_goal
        ]
        if not rows:
            return None
        g, r = min(rows, key=lambda gr: self.cost[gr[1]])
        m = ms.motions[ms.by_goal[g]]
        return _result(req, (g,), (self.terms(r),), self.mean[r], self.cov[r], 0, (m,), self.lib.scenario.cost)


class _Pairs:
    """Two-robot combinations of all pair requests: groups of requests with the same start
    states, each group's combinations in trie order (:func:`joint_lex_order`)."""

    def __init__(self, lib: MotionLibrary, sets: dict, requests: list[Request]):
        self.lib, self.requests = lib, requests
        self.groups: list[tuple[MotionSet, MotionSet, Request]] = []
        self.a: list[np.ndarray] = []
        self.b: list[np.ndarray] = []
        self.of_request: dict[int, tuple[int, np.ndarray]] = {}  # request -> (group, combo positions)
        self.pruned: dict[int, float] = {}  # request -> lower bound, for pairs not simulated
        group_of: dict[tuple, int] = {}
        raw: dict[int, list[tuple[int, list[tuple[int, int]]]]] = {}
        for i, req in enumerate(requests):
            if req.n != 2:
                continue
            k1, k2 = (req.robots[0], req.starts[0]), (req.robots[1], req.starts[1])
            if k1 not in sets or k2 not in sets:
                continue
            gkey = (req.robots, req.starts, req.joint_cov)
            if gkey not in group_of:
                group_of[gkey] = len(self.groups)
                self.groups.append((sets[k1], sets[k2], req))
            s1, s2 = sets[k1], sets[k2]
            mine = [
                (s1.by_goal[g1], s2.by_goal[g2])
                for g1 in lib.roadmap.instantiations[req.rooms[0]]
                for g2 in lib.roadmap.instantiations[req.rooms[1]]
                if g1 != g2 and g1 in s1.by_goal and g2 in s2.by_goal  # two robots cannot end on one pose
            ]
            raw.setdefault(group_of[gkey], []).append((i, mine))
        for g in range(len(self.groups)):
            s1, s2, _ = self.groups[g]
            combos = sorted({c for _, mine in raw.get(g, []) for c in mine})
            a = np.array([c[0] for c in combos], dtype=np.int64)
            b = np.array([c[1] for c in combos], dtype=np.int64)
            order = joint_lex_order(a, b, s1.prefix, s2.prefix) if len(combos) else np.zeros(0, dtype=np.int64)
            a, b = a[order], b[order]
            position = {(int(x), int(y)): k for k, (x, y) in enumerate(zip(a, b, strict=True))}
            self.a.append(a)
            self.b.append(b)
            for i, mine in raw.get(g, []):
                self.of_request[i] = (g, np.array([position[c] for c in mine], dtype=np.int64))

    def run(self, stats: EvalStats, singles: _Singles) -> None:
        """Mutual visibility of every combo, factorisation, pruning, then the joint simulations."""
        lib = self.lib
        G = len(self.groups)
        self.seen: list[np.ndarray] = [np.zeros(a.shape[0], dtype=bool) for a in self.a]
        first_all: np.ndarray | None = None
        self.kept_row: list[np.ndarray] = [np.full(a.shape[0], -1, dtype=np.int64) for a in self.a]
        if G == 0 or not any(a.shape[0] for a in self.a):
            return
        table = MotionTable.of_sets(
            [ms for s1, s2, _ in self.groups for ms in (s1, s2)], lib.world.landmark_xy.shape[0], lib.scenario.models.dt
        )
        ids1 = [table.ids(self.groups[g][0], self.a[g]) for g in range(G)]
        ids2 = [table.ids(self.groups[g][1], self.b[g]) for g in range(G)]
        horizon = [np.maximum(self.groups[g][0].steps[self.a[g]], self.groups[g][1].steps[self.b[g]]) for g in range(G)]
        start = [
            _chain(self.groups[g][0].prefix, self.a[g], horizon[g], self.groups[g][1].prefix, self.b[g])
            for g in range(G)
        ]
        c_motion = np.column_stack([np.concatenate(ids1), np.concatenate(ids2)])
        c_horizon = np.concatenate(horizon)
        vis_start = np.concatenate([np.concatenate([[-1], s[1:]]) if s.shape[0] else s for s in start])
        c_off = np.concatenate([[0], np.cumsum(c_horizon + 1)[:-1]]).astype(np.int64)
        mvis = np.zeros((int((c_horizon + 1).sum()), 2, 2), dtype=bool)
        if lib.scenario.models.mutual_observations:
            sensor = lib.scenario.models.mutual_sensor
            grid = lib.world.grid
            radii = np.concatenate(
                [
                    np.full(
                        self.a[g].shape[0], lib.scenario.robot(s1.robot).radius + lib.scenario.robot(s2.robot).radius
                    )
                    for g, (s1, s2, _) in enumerate(self.groups)
                ]
            )
            first_all = np.full(c_horizon.shape[0], -1, dtype=np.int64)
            for r in np.unique(radii):  # one call per radius sum: teams mostly share one size
                sel = np.nonzero(radii == r)[0]
                st = vis_start[sel].copy()
                st[1:][np.diff(sel) != 1] = -1  # a gap breaks the chain of shared prefixes
                first_all[sel] = mutual_visibility_sequences(
                    grid.occupied,
                    lib.world.clearance,
                    grid.origin[0],
                    grid.origin[1],
                    grid.resolution,
                    sensor.range,
                    float(r),
                    sensor.fov,
                    table.off,
                    table.T,
                    table.pose,
                    c_motion[sel],
                    st,
                    c_horizon[sel],
                    c_off[sel],
                    mvis,
                )
            bounds = np.cumsum([0] + [a.shape[0] for a in self.a])
            self.seen = [first_all[bounds[g] : bounds[g + 1]] >= 0 for g in range(G)]
        bounds = np.cumsum([0] + [a.shape[0] for a in self.a])
        first = [
            first_all[bounds[g] : bounds[g + 1]] if first_all is not None else np.full(self.a[g].shape[0], -1)
            for g in range(G)
        ]
        needed = self.prune(first, singles, stats)
        # simulate jointly what cannot be factorised (and is not pruned)
        groups, cg, cm, cs, ch, co = [], [], [], [], [], []
        bounds = np.cumsum([0] + [a.shape[0] for a in self.a])
        rows = 0
        for g, (s1, s2, req) in enumerate(self.groups):
            keep = (self.seen[g] | (req.joint_cov is not None)) & needed[g]
            stats.joint_factorized += int((~self.seen[g] & needed[g]).sum()) if req.joint_cov is None else 0
            k = np.nonzero(keep)[0]
            if k.size == 0:
                continue
            groups.append((req.mean0(), req.cov0(), mutual_seed(lib, req.robots, req.starts)))
            cg.append(np.full(k.size, len(groups) - 1, dtype=np.int64))
            cm.append(c_motion[bounds[g] + k])
            cs.append(_chain(s1.prefix, self.a[g][k], horizon[g][k], s2.prefix, self.b[g][k]))
            ch.append(horizon[g][k])
            co.append(c_off[bounds[g] + k])
            self.kept_row[g][k] = rows + np.arange(k.size)
            rows += k.size
        stats.joint_sims += rows
        if rows == 0:
            return
        c_group, c_mot, c_start, c_hor, c_moff = (np.concatenate(x) for x in (cg, cm, cs, ch, co))
        self.mean, self.cov, csig, fxy, self.mutual, _, _, _ = _simulate(
            lib, table, 2, groups, c_group, c_mot, c_start, c_hor, c_moff, mvis
        )
        goal_xy = table.pose[table.off[c_mot] + c_mot + table.T[c_mot], :2]  # (rows, 2, 2)
        self.c_u = table.c_u[c_mot]
        self.c_g = np.hypot(fxy[..., 0] - goal_xy[..., 0], fxy[..., 1] - goal_xy[..., 1])
        self.c_sigma = csig
        w = lib.scenario.cost
        self.cost = (w.M_u * self.c_u + w.M_G * self.c_g + w.M_Sigma * self.c_sigma).sum(axis=1)
        stats.steps_total += int(c_hor.sum())
        stats.steps_computed += int((c_hor - c_start).sum())

    def singles_needed(self) -> list[tuple[MotionSet, np.ndarray]]:
        """Every motion the combos use, simulated alone: factorised combos are sums of these,
        and their running c_Sigma bounds the joint cost (see :meth:`prune`)."""
        out = []
        for g, (s1, s2, _) in enumerate(self.groups):
            out.append((s1, self.a[g]))
            out.append((s2, self.b[g]))
        return out

    def prune(self, first: list[np.ndarray], singles: _Singles, stats: EvalStats) -> list[np.ndarray]:
        """Requests that provably cannot save ``min_gain``; returns, per group, the combos
        still worth simulating jointly.

        Until the robots first see each other (step k0), their joint EKF equals the two
        single ones (uncorrelated starts, separate noise streams): the joint cost of a
        combination is at least M_u (c_u1 + c_u2) + M_Sigma (C1(k0 - 1) + C2(k0 - 1)), with
        C_i the running c_Sigma of robot i alone, since trace(Sigma) and c_G are never
        negative. A factorised combination costs exactly the sum of its singles.
        """
        w = self.lib.scenario.cost
        needed = [np.zeros(a.shape[0], dtype=bool) for a in self.a]
        self.pruned = {}
        for i, (g, positions) in self.of_request.items():
            req = self.requests[i]
            s1, s2, _ = self.groups[g]
            if req.min_gain is None or req.joint_cov is not None or positions.size == 0:
                needed[g][positions] = True
                continue
            bound = np.inf
            for p in positions:
                r1, r2 = singles.index(s1, int(self.a[g][p])), singles.index(s2, int(self.b[g][p]))
                k0 = int(first[g][p])
                if k0 < 0:
                    bound = min(bound, singles.cost[r1] + singles.cost[r2])
                    continue
                before = max(k0 - 1, 0)
                h1, h2 = singles.csig_hist[r1], singles.csig_hist[r2]
                c1 = h1[min(before, int(s1.steps[self.a[g][p]]))]
                c2 = h2[min(before, int(s2.steps[self.b[g][p]]))]
                bound = min(bound, w.M_u * (singles.c_u[r1] + singles.c_u[r2]) + w.M_Sigma * (c1 + c2))
            alone = singles.best_cost(s1, req.rooms[0]) + singles.best_cost(s2, req.rooms[1])
            if bound > (1.0 - req.min_gain) * alone + 1e-9 * alone + 0.002:
                self.pruned[i] = float(bound)
                stats.pairs_pruned += 1
            else:
                needed[g][positions] = True
        return needed

    def best(self, i: int, singles: _Singles) -> MotionResult | None:
        if i not in self.of_request or self.of_request[i][1].size == 0:
            return None
        if i in self.pruned:
            req = self.requests[i]
            return MotionResult(self.pruned[i], req.robots, (), (), (), (), (), pruned=True)
        g, positions = self.of_request[i]
        s1, s2, _req = self.groups[g]
        costs = np.empty(positions.size)
        for k, p in enumerate(positions):  # in the request's own (product) order: ties -> first
            row = self.kept_row[g][p]
            if row >= 0:
                costs[k] = self.cost[row]
            else:
                costs[k] = (
                    singles.cost[singles.index(s1, int(self.a[g][p]))]
                    + singles.cost[singles.index(s2, int(self.b[g][p]))]
                )
        p = positions[int(np.argmin(costs))]
        a, b = int(self.a[g][p]), int(self.b[g][p])
        m1, m2 = s1.motions[a], s2.motions[b]
        row = self.kept_row[g][p]
        if row >= 0:
            terms = tuple(
                CostTerms(float(self.c_u[row, j]), float(self.c_g[row, j]), float(self.c_sigma[row, j]))
                for j in range(2)
            )
            return _result(
                self.requests[i],
                (m1.path[-1], m2.path[-1]),
                terms,
                self.mean[row],
                self.cov[row],
                int(self.mutual[row]),
                (m1, m2),
                self.lib.scenario.cost,
            )
        r1, r2 = singles.index(s1, a), singles.index(s2, b)
        mean = np.concatenate([singles.mean[r1], singles.mean[r2]])
        cov = np.zeros((6, 6))
        cov[:3, :3], cov[3:, 3:] = singles.cov[r1], singles.cov[r2]  # factorised: block-diagonal
        return _result(
            self.requests[i],
            (m1.path[-1], m2.path[-1]),
            (singles.terms(r1), singles.terms(r2)),
            mean,
            cov,
            0,
            (m1, m2),
            self.lib.scenario.cost,
        )


def _result(
    req: Request,
    goals: tuple[int, ...],
    terms: tuple[CostTerms, ...],
    mean: np.ndarray,
    cov: np.ndarray,
    mutual_steps: int,
    motions: tuple[NominalMotion, ...],
    weights: CostWeights,
) -> MotionResult:
    return MotionResult(
        cost=float(sum(t.total(weights) for t in terms)),
        robots=req.robots,
        goal_nodes=tuple(int(g) for g in goals),
        paths=tuple(m.path for m in motions),
        terms=tuple(terms),
        final_mean=tuple(float(v) for v in mean),
        final_cov=tuple(tuple(float(v) for v in row) for row in cov),
        mutual_steps=mutual_steps,
        final_headings=tuple(m.final_heading for m in motions),
    )
