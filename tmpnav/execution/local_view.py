"""What a nav2 robot's costmaps give its controller in ``tmpnav simulate``: the walls where its
lidar sees them, not where its estimate puts them.

nav2 marks obstacles in its costmaps from the live scans, each placed from the robot's own
pose: a robot whose AMCL estimate is a few decimetres off still sees the door frame beside it
where it is, and its planner and controller keep clear of what they see. A follower that
steered on the global estimate alone (``--steer estimate``) would drive that error into the
walls; the collision bound of ``models.range_sensor.localiser.walls: local`` prices the error
that is left (docs/models.md, "The collision bound against the walls a robot sees").

The model (``--steer local``): at each control step the robot takes the returns of its lidar
within :data:`LOCAL_REACH` (the site's walls, clutter and people, from its true pose: what its
local costmap holds), places them from its estimate, and moves the estimate so that they lie on
the map's walls (a few Gauss-Newton steps on their distances in the map's signed distance field,
the returns far from every wall left out). It steers on that pose; its localiser's estimate is
left as it is. What remains is the site's difference from the map (walls a few centimetres off),
the lidar's noise and the controller's lag. Too few returns nearby, or no fit within
:data:`MAX_SHIFT`, and the estimate steers alone. Each command is then checked against what the
robot sees (:meth:`LocalView.safe_command`).

A robot whose estimate is half a metre or more off, where the returns cannot place it, may find
every command towards its waypoint refused (the waypoint lies behind a wall in truth): nav2's
recovery behaviours then take over (:mod:`.recovery`). The other robots within 2.5 m are in the
costmap where they truly are, as nav2's obstacle layer marks what the lidar sees (a disc of
their radius); the returns that place the robot are the site's alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from tmpnav.execution.site import Site
from tmpnav.types import RangeSensor

LOCAL_REACH = 2.0  # m: the returns nearer than this place the robot among the walls it sees
#: m: at each Gauss-Newton step of the placement, a return this far from every mapped wall (as
#: placed so far) is left out: coarse to fine, so that an estimate half a metre off is placed, and
#: at the end what lies off every wall is something else (clutter, a person)
GATES = (1.0, 0.6, 0.3, 0.3)
MIN_POINTS = 6  # fewer nearby returns place nothing
#: the weight of a prior that keeps the placement still along what the returns do not fix (a
#: bare corridor's length), as much as a twentieth of one return's
PRIOR = 0.05
MAX_SHIFT = 1.5  # m: a placement farther than this is no fit: the estimate steers alone
#: s: how far ahead the controller checks its command against what it sees (nav2's RPP checks 1.5 s)
HORIZON = 1.5
ROLLOUT_DT = 0.1  # s: the rollout's samples
#: m: the room the controller keeps between its footprint and what it sees (a costmap cell)
KEEP_CLEAR = 0.05
TARGET_SLACK = 0.02  # m: how much nearer than its target's the way there may come to what the robot sees
FAN = 6  # turn rates on each side of straight that the controller tries instead of a command


class LocalView:
    """The steering pose of every robot of a session that keeps clear of the walls it sees."""

    def __init__(self, site: Site, sensor: RangeSensor):
        self.site, self.sensor = site, sensor
        self.angles = sensor.beam_angles()
        grid = site.world.grid
        self.sdf = site.world.signed_distance  # the map's: what the robot's estimate is placed in
        self.x0, self.y0 = (float(v) for v in grid.origin)
        self.res = float(grid.resolution)
        self._walls = site.walls()  # the site's walls, exact (its field is a lower bound away from the clutter)
        #: (k, 3) m: the other robots the lidar sees now, centre and radius (set by the navigator each step)
        self.robots = np.zeros((0, 3))

    def steering_pose(self, est: np.ndarray, truth: np.ndarray, t: float = 0.0) -> np.ndarray:
        """The pose (3,) the robot steers on: its estimate ``est`` moved so that what its lidar sees
        nearby from its true pose ``truth`` (at time ``t``, s) lies on the map's walls."""
        near = self._near_endpoints(truth, t)
        if near.shape[0] < MIN_POINTS:
            return est
        c, s_ = math.cos(float(est[2])), math.sin(float(est[2]))
        points = np.column_stack([est[0] + c * near[:, 0] - s_ * near[:, 1], est[1] + s_ * near[:, 0] + c * near[:, 1]])
        shift = np.zeros(2)
        for gate in GATES:  # Gauss-Newton on the points' distances to the mapped walls
            d, g = _sample_gradient(self.sdf, self.x0, self.y0, self.res, points + shift)
            keep = np.abs(d) < gate
            if np.count_nonzero(keep) < MIN_POINTS:
                return est
            gk, dk = g[keep], d[keep]
            H = gk.T @ gk + PRIOR * np.eye(2)  # no move along what the points do not constrain
            shift -= np.linalg.solve(H, gk.T @ dk)
            norm = float(np.hypot(*shift))
            if norm > MAX_SHIFT:
                return est  # no nearby fit: the estimate is too far off for the costmap to place it
        return np.array([est[0] + shift[0], est[1] + shift[1], est[2]])

    def _near_endpoints(self, truth: np.ndarray, t: float) -> np.ndarray:
        """The endpoints (P, 2), in the robot's frame, of the lidar's returns within
        :data:`LOCAL_REACH` of the robot: what its local costmap holds."""
        ranges = self.site.ranges(truth, self.angles, self.sensor, t)
        close = ~np.isnan(ranges) & (ranges < LOCAL_REACH)
        r, a = ranges[close], self.angles[close]
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    def safe_command(
        self,
        truth: np.ndarray,
        command: np.ndarray,
        radius: float,
        limits: tuple[float, float],
        ahead: float,
        target: np.ndarray | None = None,
    ) -> np.ndarray | None:
        """The command (v, omega) the controller drives instead of ``command`` so that the robot's
        footprint, rolled out from its true pose ``truth`` for :data:`HORIZON` or until it has
        driven ``ahead`` (m, to where it is going: it stops there), keeps :data:`KEEP_CLEAR` from
        every surface it sees (no nearer than it is now): ``command`` itself when it does, else
        the nearest of a fan of speeds and turn rates within ``limits`` (speed, turn rate) that
        does, as nav2's controllers score their trajectories against the local costmap; standing
        and None when none does. A ``target`` (x, y) nearer than that to what the robot sees
        (a goal pose beside a shelf) may be driven up to."""
        v, omega = float(command[0]), float(command[1])
        if v <= 0.0:
            return command  # turning on the spot moves no footprint
        speed, turn = limits
        now = self.clearance(truth[None, :2])[0] - radius
        need = min(KEEP_CLEAR, now)
        if target is not None:  # it may go as near what it sees as where it is going is
            at = self.clearance(np.asarray(target, dtype=float)[None, :2])[0]
            need = min(need, at - radius - TARGET_SLACK)
        vs = np.array([v, 0.5 * v] * (2 * FAN + 2))
        omegas = np.repeat(np.r_[omega, np.linspace(-turn, turn, 2 * FAN + 1)], 2)
        clear = _rollouts(self.clearance, truth, vs, omegas, ahead) - radius
        ok = clear >= need
        if ok[0]:
            return command
        if not ok.any():
            return None
        cost = np.abs(omegas - omega) / max(turn, 1e-9) + np.abs(vs - v) / max(speed, 1e-9)
        k = int(np.argmin(np.where(ok, cost, np.inf)))
        return np.array([vs[k], omegas[k]])

    def clear_path(self, truth: np.ndarray, v: float, radius: float, horizon: float) -> bool:
        """Whether driving straight at ``v`` (m/s; negative: backwards) from the true pose ``truth``
        for ``horizon`` seconds keeps the footprint clear of what the robot sees (no nearer than it
        is now, nor than :data:`KEEP_CLEAR`), as nav2's behaviours check their motion."""
        now = self.clearance(truth[None, :2])[0] - radius
        clear = _rollouts(self.clearance, truth, np.array([v]), np.zeros(1), horizon=horizon)
        return bool(clear[0] - radius >= min(KEEP_CLEAR, now))

    def clearance(self, xy: np.ndarray) -> np.ndarray:
        """The distance (P,) m from the points xy (P, 2) to the nearest surface of the site the
        robot sees: its walls (bilinear in their field), its clutter boxes (exact) and the other
        robots in sight (:attr:`robots`, as nav2's obstacle layer marks them). The site's
        own field is exact only near the boxes and a lower bound beyond (what its ray casts need),
        too low to judge a footprint's room by."""
        d = _sample_gradient(self._walls, self.x0, self.y0, self.res, xy)[0]
        boxes = self.site.boxes
        if len(boxes):
            d = np.minimum(d, _box_distance(xy, boxes, self.site.noise.clutter_size))
        if len(self.robots):  # the other robots, where the lidar sees them
            gaps = np.hypot(xy[:, 0, None] - self.robots[None, :, 0], xy[:, 1, None] - self.robots[None, :, 1])
            d = np.minimum(d, (gaps - self.robots[None, :, 2]).min(axis=1))
        return d


def _box_distance(xy: np.ndarray, boxes: np.ndarray, size: float) -> np.ndarray:
    """The signed distance (P,) m from the points xy (P, 2) to the nearest of the square boxes
    (N, 3: centre x, y and heading) of side ``size``."""
    gx = xy[:, 0, None] - boxes[None, :, 0]
    gy = xy[:, 1, None] - boxes[None, :, 1]
    c, s = np.cos(boxes[None, :, 2]), np.sin(boxes[None, :, 2])
    lx = np.abs(c * gx + s * gy) - 0.5 * size
    ly = np.abs(-s * gx + c * gy) - 0.5 * size
    d = np.hypot(np.maximum(lx, 0.0), np.maximum(ly, 0.0)) + np.minimum(np.maximum(lx, ly), 0.0)
    return d.min(axis=1)


def _rollouts(
    clearance: Callable[[np.ndarray], np.ndarray],
    pose: np.ndarray,
    vs: np.ndarray,
    omegas: np.ndarray,
    ahead: float = math.inf,
    horizon: float = HORIZON,
) -> np.ndarray:
    """The least ``clearance`` along each arc driven at (vs[k], omegas[k]) from ``pose`` for
    ``horizon`` seconds or ``ahead`` metres, whichever ends first, sampled every
    :data:`ROLLOUT_DT` (the first sample always) -> (K,)."""
    t = np.arange(1, round(horizon / ROLLOUT_DT) + 1) * ROLLOUT_DT
    th = pose[2] + omegas[:, None] * t
    small = np.abs(omegas) < 1e-9
    w = np.where(small, 1.0, omegas)[:, None]
    x = np.where(
        small[:, None],
        pose[0] + vs[:, None] * t * np.cos(pose[2]),
        pose[0] + vs[:, None] / w * (np.sin(th) - np.sin(pose[2])),
    )
    y = np.where(
        small[:, None],
        pose[1] + vs[:, None] * t * np.sin(pose[2]),
        pose[1] - vs[:, None] / w * (np.cos(th) - np.cos(pose[2])),
    )
    values = clearance(np.column_stack([x.ravel(), y.ravel()])).reshape(x.shape)
    beyond = (np.abs(vs)[:, None] * t[None, :] > ahead) & (t[None, :] > ROLLOUT_DT)
    return np.where(beyond, np.inf, values).min(axis=1)


def _sample_gradient(
    field: np.ndarray, x0: float, y0: float, res: float, xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``field`` at the points xy (P, 2), bilinear between cell centres, and its gradient (P, 2)
    (off the grid: -res/2 and no gradient)."""
    u = (xy[:, 0] - x0) / res - 0.5
    v = (xy[:, 1] - y0) / res - 0.5
    j, i = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    fx, fy = u - j, v - i
    rows, cols = field.shape
    inside = (i >= 0) & (i < rows - 1) & (j >= 0) & (j < cols - 1)
    i, j = np.clip(i, 0, rows - 2), np.clip(j, 0, cols - 2)
    f00, f01, f10, f11 = field[i, j], field[i, j + 1], field[i + 1, j], field[i + 1, j + 1]
    a = f00 + (f01 - f00) * fx
    b = f10 + (f11 - f10) * fx
    gx = ((f01 - f00) * (1.0 - fy) + (f11 - f10) * fy) / res
    value = np.where(inside, a + (b - a) * fy, -0.5 * res)
    gradient = np.where(inside[:, None], np.column_stack([gx, (b - a) / res]), 0.0)
    return value, gradient
