"""What a nav2 robot's costmaps give its controller in ``tmpnav simulate``: the walls where its
lidar sees them, not where its estimate puts them.

nav2 marks obstacles in its costmaps from the live scans, each placed from the robot's own
pose: a robot whose AMCL estimate is a few decimetres off still sees the door frame beside it
where it is, and its planner and controller keep clear of what they see. A follower that
steered on the global estimate alone (``--steer estimate``) would drive that error into the
walls; the collision bound of ``models.range_sensor.localiser.walls: local`` prices the error
that is left (docs/models.md, "The collision bound against the walls a robot sees").

The model (``--steer local``): at each control step the robot reads from its local costmap its
distance to the nearest surface it sees (the site's walls and clutter, from its true pose, to the
costmap's cell), and moves its estimate along the normal of the mapped wall nearest to the
estimate by the difference between that distance and the estimate's distance to the mapped
wall. It steers on that pose; its localiser's estimate is left as it is. What remains is the
site's difference from the map (walls a few centimetres off), the costmap's cells and the
controller's lag. A surface whose distance differs from the map's by more than :data:`GATE` is
something else (clutter, a person, another wall) and corrects nothing; walls farther than
:data:`LOCAL_REACH` do not correct it either, as a wall that far does not constrain the path,
and the correction fades in over :data:`FADE` so that the steering pose does not jump.

Not modelled: the global planner failing where the map and the scan disagree by more than a
door's slack (nav2 would clear its costmaps and plan again: time lost, not a wall hit), and
other robots in the costmap.
"""

from __future__ import annotations

import math

import numpy as np

from tmpnav.execution.site import Site

LOCAL_REACH = 1.0  # m: a mapped wall farther from the estimate than this corrects nothing
FADE = 0.4  # m: the correction fades in from LOCAL_REACH to LOCAL_REACH - FADE
COSTMAP_RESOLUTION = 0.05  # m: nav2's local costmap cells (its default resolution)
#: m: a surface seen nearer or farther than this from where the map puts the nearest wall is
#: something else (clutter, a person, another wall): it does not correct the steering
GATE = 0.5
#: s: how far ahead the controller checks its command against what it sees (nav2's RPP checks 1.5 s)
HORIZON = 1.5
ROLLOUT_DT = 0.1  # s: the rollout's samples
#: m: the room the controller keeps between its footprint and what it sees (a costmap cell)
KEEP_CLEAR = 0.05
FAN = 6  # turn rates on each side of straight that the controller tries instead of a command


class LocalView:
    """The steering pose of every robot of a session that keeps clear of the walls it sees."""

    def __init__(self, site: Site):
        self.site = site
        grid = site.world.grid
        self.sdf = site.world.signed_distance  # the map's: what the robot's estimate is placed in
        self.x0, self.y0 = (float(v) for v in grid.origin)
        self.res = float(grid.resolution)

    def steering_pose(self, est: np.ndarray, truth: np.ndarray) -> np.ndarray:
        """The pose (3,) the robot steers on: its estimate ``est`` moved along the nearest mapped
        wall's normal by the difference between its distance to the nearest surface it sees from
        its true pose ``truth`` and its estimate's distance to the nearest mapped wall."""
        d_map, gx, gy = _bilinear(self.sdf, self.x0, self.y0, self.res, float(est[0]), float(est[1]))
        norm = math.hypot(gx, gy)
        if d_map >= LOCAL_REACH or norm < 1e-9:
            return est
        seen = _bilinear(self.site.field, self.x0, self.y0, self.res, float(truth[0]), float(truth[1]))[0]
        seen = (math.floor(seen / COSTMAP_RESOLUTION) + 0.5) * COSTMAP_RESOLUTION  # the costmap's cell
        if abs(seen - d_map) > GATE:
            return est  # what it sees nearest is not the mapped wall (clutter, another wall): no correction
        weight = min(1.0, max(0.0, (LOCAL_REACH - min(d_map, seen)) / FADE))
        shift = weight * (seen - d_map)
        return np.array([est[0] + shift * gx / norm, est[1] + shift * gy / norm, est[2]])

    def safe_command(
        self, truth: np.ndarray, command: np.ndarray, radius: float, limits: tuple[float, float]
    ) -> np.ndarray:
        """The command (v, omega) the controller drives instead of ``command`` so that the robot's
        footprint, rolled out :data:`HORIZON` ahead from its true pose ``truth``, keeps
        :data:`KEEP_CLEAR` from every surface it sees (no nearer than it is now): ``command``
        itself when it does, else the nearest of a fan of speeds and turn rates within ``limits``
        (speed, turn rate) that does, as nav2's controllers score their trajectories against the
        local costmap; standing and turning when none does."""
        v, omega = float(command[0]), float(command[1])
        if v <= 0.0:
            return command  # turning on the spot moves no footprint
        speed, turn = limits
        now = _sample(self.site.field, self.x0, self.y0, self.res, truth[None, :2])[0] - radius
        need = min(KEEP_CLEAR, now)
        vs = np.array([v, 0.5 * v] * (2 * FAN + 2))
        omegas = np.repeat(np.r_[omega, np.linspace(-turn, turn, 2 * FAN + 1)], 2)
        clear = _rollouts(self.site.field, self.x0, self.y0, self.res, truth, vs, omegas) - radius
        ok = clear >= need
        if ok[0]:
            return command
        if not ok.any():
            return np.array([0.0, omega])
        cost = np.abs(omegas - omega) / max(turn, 1e-9) + np.abs(vs - v) / max(speed, 1e-9)
        k = int(np.argmin(np.where(ok, cost, np.inf)))
        return np.array([vs[k], omegas[k]])


def _rollouts(
    field: np.ndarray, x0: float, y0: float, res: float, pose: np.ndarray, vs: np.ndarray, omegas: np.ndarray
) -> np.ndarray:
    """The least value of ``field`` along each arc driven at (vs[k], omegas[k]) from ``pose`` for
    :data:`HORIZON` seconds, sampled every :data:`ROLLOUT_DT` -> (K,)."""
    t = np.arange(1, round(HORIZON / ROLLOUT_DT) + 1) * ROLLOUT_DT
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
    values = _sample(field, x0, y0, res, np.column_stack([x.ravel(), y.ravel()]))
    return values.reshape(x.shape).min(axis=1)


def _sample(field: np.ndarray, x0: float, y0: float, res: float, xy: np.ndarray) -> np.ndarray:
    """``field`` at the points xy (P, 2), bilinear between cell centres (-res/2 off the grid)."""
    u = (xy[:, 0] - x0) / res - 0.5
    v = (xy[:, 1] - y0) / res - 0.5
    j, i = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    fx, fy = u - j, v - i
    padded = np.pad(field, 1, constant_values=-0.5 * res)
    rows, cols = padded.shape
    i0, j0 = np.clip(i + 1, 0, rows - 2), np.clip(j + 1, 0, cols - 2)
    inside = (i + 1 == i0) & (j + 1 == j0)
    f00, f01 = padded[i0, j0], padded[i0, j0 + 1]
    f10, f11 = padded[i0 + 1, j0], padded[i0 + 1, j0 + 1]
    a = f00 + (f01 - f00) * fx
    b = f10 + (f11 - f10) * fx
    return np.where(inside, a + (b - a) * fy, -0.5 * res)


def _bilinear(field: np.ndarray, x0: float, y0: float, res: float, x: float, y: float) -> tuple[float, float, float]:
    """A signed distance field (m) at (x, y), bilinear between cell centres, and its gradient
    (off the grid: -res/2, as tmpnav.world.lidar reads it)."""
    u = (x - x0) / res - 0.5
    v = (y - y0) / res - 0.5
    j, i = math.floor(u), math.floor(v)
    fx, fy = u - j, v - i
    rows, cols = field.shape

    def at(r: int, c: int) -> float:
        return float(field[r, c]) if 0 <= r < rows and 0 <= c < cols else -0.5 * res

    f00, f01, f10, f11 = at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1)
    a = f00 + (f01 - f00) * fx
    b = f10 + (f11 - f10) * fx
    gx = ((f01 - f00) * (1.0 - fy) + (f11 - f10) * fy) / res
    return a + (b - a) * fy, gx, (b - a) / res
