"""The team localised by nav2's AMCL in ``tmpnav simulate --localiser amcl``: one particle filter
per robot (:class:`tmpnav.execution.amcl.AmclLocaliser`), fed with its odometry (the commands
integrated from its initial estimate: the wheels' error is the control noise) and its lidar's
scans of a site that differs from the map (:mod:`tmpnav.execution.site`)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tmpnav.belief.models import motion
from tmpnav.errors import TmpnavError
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import QueuedMove
from tmpnav.execution.trace import Draws
from tmpnav.types import Belief, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility


class AmclTeam:
    """Every robot's AMCL, started at its initial ``belief`` (the joint one's blocks)."""

    def __init__(
        self,
        scenario: Scenario,
        world: World,
        draws: Draws,
        belief: Belief,
        localisation: Localisation,
        queues: Mapping[str, tuple[QueuedMove, ...]],
        session: int,
    ):
        from tmpnav.execution.amcl import AmclLocaliser
        from tmpnav.execution.site import Site, SiteNoise

        sensor = scenario.models.range_sensor
        if sensor is None:
            raise TmpnavError(
                "--localiser amcl: the scenario's robots carry no range sensor (models.range_sensor); "
                "expected a scenario with a lidar (AMCL localises with it)"
            )
        self.scenario, self.draws, self.sensor = scenario, draws, sensor
        n = len(scenario.robots)
        noise = localisation.site or SiteNoise.none()
        paths = [np.asarray(m.points, dtype=float).reshape(-1, 2) for q in queues.values() for m in q]
        self.site = Site(world, noise, session, keep_clear=paths or None)  # no clutter on the paths
        self.odom = np.array(belief.mean, dtype=float).reshape(n, 3)
        blocks = [slice(3 * i, 3 * i + 3) for i in range(n)]
        self.localisers = [
            # the process's AMCL random stream is seeded by the session (the last filter's seed holds)
            AmclLocaliser(world.grid, sensor, localisation.amcl, self.odom[i], belief.cov[b, b], seed=session + 1)
            for i, b in enumerate(blocks)
        ]

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's pose estimate (3,): its AMCL's."""
        return self.localisers[i].mean

    def estimate_cov(self, i: int) -> np.ndarray:
        """Robot i's covariance (3, 3) as its AMCL reports it."""
        return self.localisers[i].cov

    def predict(self, u: np.ndarray, steps: np.ndarray | None = None) -> None:
        """Odometry: the commands (n, 2) integrated; with ``steps`` (n, N, 2), one by one, each on
        its arc (the midpoint step the true robot drives them by, tmpnav.execution.rpp.drive)."""
        dt = self.scenario.models.dt
        if steps is None:
            self.odom = motion(self.odom, u, dt)
            return
        for k in range(steps.shape[1]):
            self.odom = motion(self.odom, steps[:, k], dt / steps.shape[1], midpoint=True)

    def observe(self, truth: np.ndarray, step: int) -> list[tuple[int, int]]:
        """Each robot's lidar scans the site from its true pose (the sensor's range noise on every
        return), and its AMCL updates with the scan and its odometry; per robot, the beams that
        returned (AMCL has no innovation gate: none rejected)."""
        sensor, t = self.sensor, step * self.scenario.models.dt
        angles = sensor.beam_angles()
        beams = []
        for i, localiser in enumerate(self.localisers):
            ranges = self.site.ranges(truth[i], angles, sensor, t) + sensor.sigma_range * self.draws.scan[i, step]
            localiser.update(self.odom[i], ranges)
            beams.append((int(np.count_nonzero(~np.isnan(ranges))), 0))
        return beams

    def set_world(self, world: World, vis: LandmarkVisibility) -> None:
        """The site keeps its clutter and people; the doors close on its walls."""
        self.site = self.site.with_world(world)
