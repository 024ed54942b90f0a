"""The team's joint EKF in ``tmpnav simulate``: the reference, through filterpy.

:class:`JointEkf` estimates every robot of a session in one joint belief
(:mod:`tmpnav.belief.ekf`, the filterpy reference): it predicts with the commands and
updates with the landmarks each robot sees, its range scan (:mod:`tmpnav.execution.scans`)
and, with mutual observations, the robots that see each other. The compiled twin that
sessions run (:mod:`tmpnav.execution.fast_ekf`) is held to it.
"""

from __future__ import annotations

import numpy as np

from tmpnav.belief import ekf
from tmpnav.belief.models import landmark_obs, mutual_obs, noisy_observation
from tmpnav.execution.localisers import substep_noise
from tmpnav.execution.scans import ScanSimulator
from tmpnav.execution.trace import Draws
from tmpnav.types import Belief, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility, MutualSensing


class JointEkf:
    """One joint EKF over the team (``mutual``: with mutual observations, config 1)."""

    def __init__(
        self, scenario: Scenario, world: World, vis: LandmarkVisibility, draws: Draws, belief: Belief, mutual: bool
    ):
        self.scenario, self.world, self.vis, self.draws, self.belief = scenario, world, vis, draws, belief
        self.names = tuple(r.name for r in scenario.robots)
        self.sensing = sensing_pairs(scenario, self.names) if mutual else {}
        sensor = scenario.models.range_sensor
        self.scans = ScanSimulator(world, sensor) if sensor is not None else None

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's estimated pose (3,): its part of the joint belief's mean."""
        return self.belief.mean[3 * i : 3 * i + 3]

    def estimate_cov(self, i: int) -> np.ndarray:
        """Robot i's covariance (3, 3): its block of the joint belief's."""
        return self.belief.cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]

    def predict(self, u: np.ndarray, steps: np.ndarray | None = None) -> None:
        """The prediction with the commands (n, 2) of the step just driven; with ``steps`` (n, N, 2)
        one by one (:meth:`tmpnav.execution.localisers.TeamLocaliser.predict`), each by the midpoint
        step the true robot drives them by (tmpnav.execution.rpp.drive)."""
        models = self.scenario.models
        if steps is None:
            self.belief = ekf.predict(self.belief, u, models.dt, models.motion_noise)
            return
        alphas = tuple(substep_noise(np.asarray(models.motion_noise), steps.shape[1]).tolist())
        for k in range(steps.shape[1]):
            self.belief = ekf.predict(self.belief, steps[:, k], models.dt / steps.shape[1], alphas, midpoint=True)

    def observe(self, truth: np.ndarray, step: int) -> list[tuple[int, int]]:
        """Every robot's landmark observations from its true pose, its range scan, then every
        pair's mutual observations; per robot, the range beams used and rejected by the gate."""
        models = self.scenario.models
        q_lm = models.landmark_sensor.Q
        chol_lm = np.linalg.cholesky(q_lm)
        landmarks = self.world.landmark_xy
        seen = self.vis.visible(truth, models.landmark_sensor.fov)
        for i in range(len(self.names)):
            for lm in np.flatnonzero(seen[i]):
                z = noisy_observation(landmark_obs(truth[i], landmarks[lm]), chol_lm, self.draws.landmark[i, step, lm])
                self.belief = ekf.update_landmark(self.belief, i, landmarks[lm], z, q_lm)
        beams = [(0, 0)] * len(self.names)
        if self.scans is not None:
            for i in range(len(self.names)):
                self.belief, count = self.scans.update(self.belief, i, truth[i], self.draws.scan[i, step])
                beams[i] = (count.used, count.rejected)
        if self.sensing:
            q_mu = models.mutual_sensor.Q
            chol_mu = np.linalg.cholesky(q_mu)
            for i, j in mutually_visible(self.sensing, self.world, truth):
                z = noisy_observation(mutual_obs(truth[i], truth[j]), chol_mu, self.draws.mutual[i, j, step])
                self.belief = ekf.update_mutual(self.belief, i, j, z, q_mu)
        return beams

    def set_world(self, world: World, vis: LandmarkVisibility) -> None:
        """The world changed (a door closed): the robots' sightings and scans see the new one."""
        self.world, self.vis = world, vis
        sensor = self.scenario.models.range_sensor
        self.scans = ScanSimulator(world, sensor) if sensor is not None else None


def sensing_pairs(scenario: Scenario, names: tuple[str, ...]) -> dict[MutualSensing, list[tuple[int, int]]]:
    """The ordered pairs of robots that observe each other (config 1), grouped by sensor."""
    groups: dict[MutualSensing, list[tuple[int, int]]] = {}
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            if i != j:
                groups.setdefault(MutualSensing.of_sensor(scenario, a, b), []).append((i, j))
    return groups


def mutually_visible(
    sensing: dict[MutualSensing, list[tuple[int, int]]], world: World, truth: np.ndarray
) -> list[tuple[int, int]]:
    """The ordered pairs (observer, observed) in range and line of sight now, in team order."""
    out = []
    for sense, pairs in sensing.items():
        a, b = np.array(pairs).T
        seen = sense.visible(world, truth[a], truth[b])
        out += [p for p, s in zip(pairs, seen, strict=True) if s]
    return sorted(out)
