"""nav2's AMCL localising one simulated robot (``tmpnav simulate --localiser amcl``).

:class:`AmclLocaliser` feeds a robot's odometry and lidar scans to nav2's AMCL through the
``amcl`` package (Python bindings of nav2_amcl, GPL-3: the optional extra ``tmpnav[amcl]``,
imported only when a localiser is built). The bindings update the particle filter at every
call; the adapter keeps nav2's update thresholds, its handling of beams without a return and
its map->odom composition between updates. What the bindings do unlike nav2 (the beam model
whatever ``laser_model_type`` says, fixed KLD parameters, the seed) is in docs/amcl.md.
"""

from __future__ import annotations

import ctypes
import math
from typing import Any

import numpy as np

from tmpnav.errors import InputError
from tmpnav.scenario.nav2_params import AmclParams
from tmpnav.types import RangeSensor
from tmpnav.world.geometry import wrap_angle
from tmpnav.world.grid import OccupancyGrid

MISSING = "--localiser amcl needs nav2's AMCL bindings: pip install 'tmpnav[amcl]' (the amcl package, GPL-3)"
#: nav2's robot_model_type -> the bindings' name of the same motion model
MOTION_MODELS = {
    "nav2_amcl::DifferentialMotionModel": "differential",
    "differential": "differential",
    "nav2_amcl::OmniMotionModel": "omni",
    "omni": "omni",
}
#: KLD sampling's population error and quantile, fixed in the bindings' pf_alloc (nav2 sets pf_err, pf_z)
BINDINGS_PF_ERR, BINDINGS_PF_Z = 0.01, 3.0


def bindings() -> Any:
    """The ``amcl`` module, or an :class:`InputError` naming the extra that installs it."""
    try:
        import amcl
    except ImportError:
        raise InputError(MISSING) from None
    return amcl


class AmclLocaliser:
    """One robot's nav2 AMCL: initial ``pose`` (3,) and ``cov`` (3, 3) on ``grid``, scanning with
    ``sensor``, with nav2's ``params``.

    :meth:`update` runs the filter as nav2's amcl_node does: at the first scan (the particles
    drawn then, at the initial pose carried by the odometry moved since), then whenever the
    odometry has moved more than ``update_min_d`` in x or y or turned more than ``update_min_a``
    since the last filter update. Beams without a return, and returns at or past the range limit
    or at or before the minimum range, go to the filter at the range limit, as nav2 passes them.

    Seeding: the bindings cannot be seeded through their API. They draw from the C library's
    process-wide ``drand48`` stream, which drawing the initial particles reseeds with a
    per-process counter (1, 2, ...): without ``seed`` a run is reproducible only when its process
    starts and updates the same filters in the same order (not across worker processes). With
    ``seed`` the adapter reseeds that stream (``srand48``) right after the initial particles, for
    every filter of the process at once."""

    name = "amcl"

    def __init__(
        self,
        grid: OccupancyGrid,
        sensor: RangeSensor,
        params: AmclParams,
        pose: np.ndarray,
        cov: np.ndarray,
        *,
        seed: int | None = None,
    ) -> None:
        amcl = bindings()
        self._amcl = amcl
        # fewer beams than max_beams make the bindings' beam step 0: their update would never return
        beams = min(params.max_beams, sensor.beams)
        self.range_max = sensor.range if params.laser_max_range <= 0 else min(sensor.range, params.laser_max_range)
        self.range_min = max(sensor.min_range, params.laser_min_range)
        self.bearings = sensor.beam_angles()
        self.update_min_d, self.update_min_a = params.update_min_d, params.update_min_a
        motion = amcl.MotionParameters(params.alpha1, params.alpha2, params.alpha3, params.alpha4, params.alpha5)
        laser = amcl.LaserParameters(
            params.z_hit, params.z_short, params.z_max, params.z_rand, params.sigma_hit, params.lambda_short, 0.0, beams
        )
        self._filter = amcl.AMCL(
            params.min_particles,
            params.max_particles,
            params.recovery_alpha_slow,
            params.recovery_alpha_fast,
            motion,
            laser,
            MOTION_MODELS[params.robot_model_type],
        )
        self._filter.set_map(_occupancy(amcl, grid))
        self._filter.set_laser_pose(amcl.Vector3D(0.0, 0.0, 0.0))
        start = np.array(pose, dtype=float)
        # nav2 takes x, y and yaw of the initial covariance, not yaw's correlations (handleInitialPose)
        self._initial_cov = np.zeros((3, 3))
        self._initial_cov[:2, :2], self._initial_cov[2, 2] = np.asarray(cov, dtype=float)[:2, :2], cov[2][2]
        self._seed = seed
        self._estimate = start  # the filter's pose at its last update (before the first: the initial pose)
        self._at_update = start.copy()  # the odometry then; it starts at the initial pose
        self._odom = start.copy()  # the odometry now
        self._cov = self._initial_cov.copy()
        self.updates = 0  # filter updates so far

    def update(self, odom: np.ndarray, ranges: np.ndarray) -> bool:
        """The robot's odometry pose (3,) and its scan's ranges (B,) m at ``sensor.beam_angles()``
        (nan: no return); whether the particle filter updated with them."""
        self._odom = np.array(odom, dtype=float)
        if not self.updates:  # nav2 updates at the first scan whatever the motion
            self._start()
        else:
            dx, dy = self._odom[:2] - self._at_update[:2]
            turn = float(wrap_angle(self._odom[2] - self._at_update[2]))
            if not (abs(dx) > self.update_min_d or abs(dy) > self.update_min_d or abs(turn) > self.update_min_a):
                return False
        r = np.asarray(ranges, dtype=float)
        r = np.where(np.isnan(r) | (r >= self.range_max) | (r <= self.range_min), self.range_max, r)
        scan = self._amcl.create_laser_scan_from_list(np.column_stack([r, self.bearings]).tolist(), self.range_max)
        self._filter.update(scan, self._amcl.Vector3D(*self._odom))
        m = self._filter.get_pose_mean()
        self._estimate = np.array([m.x, m.y, m.theta])
        self._at_update = self._odom.copy()
        self._cov = self._filter_cov()
        self.updates += 1
        return True

    def _start(self) -> None:
        """The particles drawn at the initial pose carried by the odometry moved since it was given
        (nav2's handleInitialPose), just before the first scan; then the seed, if any."""
        pose = _compose(self._estimate, _between(self._at_update, self._odom))
        initial = self._amcl.Matrix3D()
        initial.from_list(self._initial_cov.tolist())
        self._filter.set_initial_pose(self._amcl.Vector3D(*pose), initial)
        if self._seed is not None:
            seed_drand48(self._seed)

    @property
    def mean(self) -> np.ndarray:
        """(3,) the pose estimate now: the filter's pose composed with the odometry moved since its
        last update (nav2's map->odom transform applied to the odometry)."""
        return _compose(self._estimate, _between(self._at_update, self._odom))

    @property
    def cov(self) -> np.ndarray:
        """(3, 3) AMCL's covariance at its last update, as nav2 publishes it: the particles' x-y
        covariance and yaw's circular variance, no correlation of yaw with x or y (before the first
        update: the initial covariance so taken)."""
        return self._cov.copy()

    def _filter_cov(self) -> np.ndarray:
        c = np.array(self._filter.get_pose_covariance().to_list(), dtype=float)
        return 0.5 * (c + c.T)


def _occupancy(amcl: Any, grid: OccupancyGrid) -> Any:
    """The grid as the bindings' map: occupied 100, free 0. AMCL puts the centre of cell (i, j)
    at origin + (j, i) resolution (nav2's MAP_WXGX), tmpnav at origin + (j + 1/2, i + 1/2)
    resolution: the origin is passed half a cell on so that both see the walls at one place."""
    half = 0.5 * grid.resolution
    cells = np.where(grid.occupied, 100, 0).tolist()
    return amcl.create_occupancy_grid_from_list(cells, grid.resolution, grid.origin[0] + half, grid.origin[1] + half)


def seed_drand48(seed: int) -> None:
    """Seed the C library's ``drand48`` stream, the one the bindings draw from (process-wide)."""
    try:
        srand48 = ctypes.CDLL(None).srand48
    except (OSError, AttributeError):
        raise InputError("--localiser amcl: this C library has no srand48; AMCL cannot be seeded here") from None
    srand48.argtypes, srand48.restype = [ctypes.c_long], None
    srand48(seed % 2**31)


def differences(params: AmclParams) -> list[str]:
    """What the bindings do unlike nav2 with ``params``, one phrase each (docs/amcl.md)."""
    out = ["pose: the mean of all particles (nav2: of the heaviest cluster)"]
    if params.laser_model_type != "beam":
        out.append(f"beam model in place of {params.laser_model_type}")
    fixed = f"pf_err {BINDINGS_PF_ERR:g}, pf_z {BINDINGS_PF_Z:g}"
    out.append(f"KLD sampling at {fixed} (nav2: pf_err {params.pf_err:g}, pf_z {params.pf_z:g})")
    if params.resample_interval != 1:
        out.append(f"resampled at every update (resample_interval {params.resample_interval} not applied)")
    return out


def _compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose a ⊕ b: b (in a's frame) carried into a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], float(wrap_angle(a[2] + b[2]))])


def _between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose a⁻¹ ⊕ b: pose b seen from pose a."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, float(wrap_angle(b[2] - a[2]))])
