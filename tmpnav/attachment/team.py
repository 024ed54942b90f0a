"""The team's state between plan steps, and the pieces of one step: who stands still, who
sees whom, the belief recorded at a control step (:mod:`tmpnav.attachment.carried`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import NominalMotion
from tmpnav.oracle.requests import Request, StartState, mutual_seed
from tmpnav.task.encodings import ENCODINGS, PairFilter
from tmpnav.types import Goals, Scenario, TrajectoryStep, cov3, vec3
from tmpnav.world.visibility import MutualSensing


@dataclass(frozen=True, eq=False)
class Team:
    """Where the robots are and what they believe, between two plan steps."""

    names: tuple[str, ...]
    node: tuple[int, ...]
    heading: tuple[float, ...]
    mean: np.ndarray  # (3N,) the team's joint belief
    cov: np.ndarray  # (3N, 3N)
    t: float = 0.0

    @staticmethod
    def at_start(lib: MotionLibrary, scenario: Scenario) -> Team:
        names = tuple(r.name for r in scenario.robots)
        cov = np.zeros((3 * len(names), 3 * len(names)))
        for i, r in enumerate(names):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = scenario.robot(r).cov
        return Team(
            names,
            tuple(lib.roadmap.starts[r] for r in names),
            tuple(scenario.robot(r).pose.theta for r in names),
            np.concatenate([scenario.robot(r).pose.as_array() for r in names]),
            cov,
        )

    def cols(self, idx: Sequence[int]) -> np.ndarray:
        return np.concatenate([np.arange(3 * i, 3 * i + 3) for i in idx]) if idx else np.zeros(0, dtype=int)

    def start_state(self, i: int) -> StartState:
        """Robot i's own state: its node, heading and marginal belief."""
        return StartState(
            self.node[i],
            float(self.heading[i]),
            vec3(self.mean[3 * i : 3 * i + 3]),
            cov3(self.cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]),
        )

    def request(self, robots: Sequence[str], rooms: Sequence[str]) -> Request:
        """The oracle's request for ``robots`` moving into ``rooms`` from where they are,
        their joint covariance included when earlier steps correlated them."""
        idx = [self.names.index(r) for r in robots]
        sub_cov = self.cov[np.ix_(self.cols(idx), self.cols(idx))]
        correlated = len(idx) > 1 and bool(np.any(sub_cov[:3, 3:] != 0.0))
        joint = tuple(tuple(float(v) for v in row) for row in sub_cov) if correlated else None
        return Request(tuple(robots), tuple(self.start_state(i) for i in idx), tuple(rooms), joint)

    def partners(self, idx: Sequence[int]) -> list[int]:
        """``idx`` and every robot correlated with one of them, in team order."""
        out = set(idx)
        for i in idx:
            block = self.cov[3 * i : 3 * i + 3]
            for j in range(len(self.names)):
                if j not in out and np.any(block[:, 3 * j : 3 * j + 3] != 0.0):
                    out.add(j)
        return sorted(out)


def stationary(lib: MotionLibrary, robot: str, node: int, heading: float) -> NominalMotion:
    """A robot that stays put during a step: no steps, no observations."""
    x, y = lib.roadmap.nodes[node]
    return NominalMotion(
        robot=robot,
        path=(node,),
        controls=np.zeros((0, 2)),
        poses=np.array([[x, y, heading]]),
        node_steps=np.zeros(1, dtype=int),
        lm_visible=np.zeros((1, lib.world.landmark_xy.shape[0]), dtype=bool),
        noise_seed=0,
        cells=lib.world.reach(lib.scenario.robot(robot).radius).cells(np.array([[x, y]])),
    )


def paired_moves(scenario: Scenario, goals: Goals, start_location: dict[str, str]) -> PairFilter:
    """The pairs of moves worth a joint cost: those the mixed encoding's entry rules let happen
    together, of two robots whose beliefs take in what they see of each other. Without that
    (mutual observations off, or nav2's AMCL fusing its lidar alone) a paired move costs exactly
    its two single moves and is never offered, so it is not asked for (building-4robots with
    the AMCL model: 69,808 joint simulations that could not save anything)."""
    keep = ENCODINGS["mixed"].pair_filter(goals, start_location)
    assert keep is not None
    return keep if scenario.models.partners_fused else lambda m1, m2: False


def mutual_sensing(
    lib: MotionLibrary,
    motions: list[NominalMotion],
    movers: list[int],
    robots: tuple[str, ...],
    starts: tuple[StartState, ...],
    h: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Who sees whom among the moving robots, and the draws the oracle used for them."""
    n = len(motions)
    mvis = np.zeros((h + 1, n, n), dtype=bool)
    mu_noise = np.zeros((h + 1, n, n, 2))
    if len(movers) == 2:
        a, b = movers
        sensing = MutualSensing.between(lib.scenario, *robots)
        if sensing is not None:
            pa, pb = motions[a].padded(h)[1], motions[b].padded(h)[1]
            mvis[:, a, b] = sensing.visible(lib.world, pa, pb)
            mvis[:, b, a] = sensing.visible(lib.world, pb, pa)
        draws = np.random.default_rng(mutual_seed(lib, robots, starts)).standard_normal((h + 1, 2, 2, 2))
        mu_noise[:, a, b], mu_noise[:, b, a] = draws[:, 0, 1], draws[:, 1, 0]
    return mvis, mu_noise


def belief_step(t: float, mean: np.ndarray, cov: np.ndarray, i: int, node: int | None) -> TrajectoryStep:
    m = mean[3 * i : 3 * i + 3]
    c = cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]
    return TrajectoryStep(t=round(float(t), 9), mean=vec3(m), cov=cov3(c), node=None if node is None else int(node))
