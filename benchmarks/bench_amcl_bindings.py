"""A check of nav2's AMCL bindings (the ``amcl`` package) through tmpnav's adapter (docs/amcl.md).

    .venv/bin/python benchmarks/bench_amcl_bindings.py        # about a minute on 2 cores

Writes benchmarks/amcl/bindings.txt and prints it. AMCL runs at nav2's defaults
(:class:`tmpnav.scenario.nav2_params.AmclParams`) with the lidar of configs/office-ros.yaml
(12 m, all round, 60 beams, 3 cm). The true scans are ray cast from the true poses
(:func:`tmpnav.world.lidar.scan`) with the sensor's noise on every return; the true robot
moves by its commands with the scenario's motion noise, and its odometry integrates the
commands (as ``tmpnav simulate`` does). Seeds 1-3: each run seeds the noise and AMCL.

* (a) office-ros: robot r1 drives from its start through rooms O5, O7 and O4 (the point of each
  farthest from the walls) along a grid path kept 0.5 m from the walls; AMCL's position error
  and its reported std at every control step, and its time per filter update.
* (b) a corridor 30 m long and 2 m wide, no feature: errors (true minus estimated) and std along
  and across it, in its middle (both ends beyond the lidar's 12 m) and nearer its ends; with
  nav2's motion noise parameters (alpha1-4 0.2) and with 0.05.
* (c) the update thresholds: filter updates over drives of known length, and the bindings'
  own update standing still (50 scans straight to the bindings, no threshold).
* (d) the map's half cell: a robot standing on a 0.2 m grid, AMCL given the map as tmpnav
  places its cells and as nav2 reads a ROS map's origin (cell centres half a cell off).
"""

from __future__ import annotations

import itertools
import math
import sys
import time
from collections import deque
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "amcl" / "bindings.txt"
SEEDS = (1, 2, 3)

from tmpnav.belief.models import motion, motion_noise_cov  # noqa: E402
from tmpnav.execution.amcl import AmclLocaliser, bindings  # noqa: E402
from tmpnav.scenario.nav2_params import AmclParams  # noqa: E402
from tmpnav.types import RangeSensor  # noqa: E402
from tmpnav.world.geometry import wrap_angle  # noqa: E402
from tmpnav.world.grid import OccupancyGrid  # noqa: E402
from tmpnav.world.lidar import scan, sensor_params, signed_distance  # noqa: E402


class Lidar:
    """True scans of one grid: ray cast, with the sensor's noise on every beam that returns."""

    def __init__(self, grid: OccupancyGrid, sensor: RangeSensor):
        self.sdf, self.grid, self.sensor = signed_distance(grid), grid, sensor
        self.angles, self.params = sensor.beam_angles(), sensor_params(sensor)

    def ranges(self, pose: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        B = self.angles.size
        r, H, var = np.empty(B), np.empty((B, 3)), np.empty(B)
        x0, y0 = self.grid.origin
        scan(self.sdf, x0, y0, self.grid.resolution, np.asarray(pose, float), self.angles, self.params, r, H, var)
        return r + np.sqrt(var) * rng.standard_normal(B)


@dataclass
class Drive:
    """What one drive recorded at every control step."""

    errors: list[np.ndarray]  # true minus estimated (x, y) m
    stds: list[np.ndarray]  # the reported std of x and y, m
    truth: list[np.ndarray]
    updates: int
    seconds: float  # in the filter's updates


def drive(grid, lidar, waypoints, start, params, alphas, dt, speed, seed) -> Drive:
    """Drive through ``waypoints`` from ``start`` (turn, then drive), AMCL localising."""
    rng = np.random.default_rng(seed)
    truth, odom = np.array(start, float), np.array(start, float)
    loc = AmclLocaliser(grid, lidar.sensor, params, odom, np.diag([0.1**2, 0.1**2, 0.05**2]), seed=seed)
    out = Drive([], [], [], 0, 0.0)
    for goal in waypoints:
        for _ in range(400):
            dx, dy = goal[0] - truth[0], goal[1] - truth[1]
            if math.hypot(dx, dy) < 0.2:
                break
            err = float(wrap_angle(math.atan2(dy, dx) - truth[2]))
            turning = abs(err) > 0.3
            u = np.array([0.0 if turning else speed, float(np.clip(2.0 * err, -1.0, 1.0))])
            noise = np.sqrt(np.diag(motion_noise_cov(u, alphas))) * rng.standard_normal(2)
            truth, odom = motion(truth, u + noise, dt), motion(odom, u, dt)
            t0 = time.perf_counter()
            if loc.update(odom, lidar.ranges(truth, rng)):
                out.updates += 1
                out.seconds += time.perf_counter() - t0
            out.errors.append(truth[:2] - loc.mean[:2])
            out.stds.append(np.sqrt(np.diag(loc.cov)[:2]))
            out.truth.append(truth.copy())
    return out


def grid_path(clearance: np.ndarray, grid: OccupancyGrid, points: list[tuple[float, float]], keep: float) -> list:
    """Waypoints every 0.5 m of the shortest 8-connected path through cells ``keep`` m from the
    walls, between the cells of that kind nearest to ``points``."""
    from scipy import ndimage

    res, (x0, y0) = grid.resolution, grid.origin
    ok = clearance >= keep
    nearest = ndimage.distance_transform_edt(~ok, return_distances=False, return_indices=True)
    cells = [(int((p[1] - y0) / res), int((p[0] - x0) / res)) for p in points]
    cells = [(int(nearest[0][c]), int(nearest[1][c])) for c in cells]
    path: list[tuple[int, int]] = []
    for a, b in itertools.pairwise(cells):
        prev = {a: a}
        queue = deque([a])
        while queue and b not in prev:
            i, j = queue.popleft()
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    n = (i + di, j + dj)
                    if n not in prev and 0 <= n[0] < ok.shape[0] and 0 <= n[1] < ok.shape[1] and ok[n]:
                        prev[n] = (i, j)
                        queue.append(n)
        leg = [b]
        while leg[-1] != a:
            leg.append(prev[leg[-1]])
        path += leg[::-1]
    step = max(1, round(0.5 / res))
    keep_idx = [*range(0, len(path), step), len(path) - 1]
    return [(x0 + (path[k][1] + 0.5) * res, y0 + (path[k][0] + 0.5) * res) for k in keep_idx]


def roomiest(world, name: str) -> tuple[float, float]:
    """The point of room ``name`` farthest from the walls."""
    from tmpnav.world.geometry import points_in_polygon

    xs, ys = world.grid.cell_centers()
    X, Y = np.meshgrid(xs, ys)
    polygon = np.asarray(next(r.polygon for r in world.rooms if r.name == name))
    inside = points_in_polygon(np.column_stack([X.ravel(), Y.ravel()]), polygon).reshape(X.shape)
    i, j = np.unravel_index(np.argmax(np.where(inside, world.clearance, -1.0)), X.shape)
    return float(xs[j]), float(ys[i])


def rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def office() -> list[str]:
    from tmpnav.pipeline import load_world

    scenario, world = load_world(ROOT / "configs" / "office-ros.yaml")
    sensor, models = scenario.models.range_sensor, scenario.models
    robot = scenario.robots[0]
    start = robot.pose.as_array()
    rooms = [roomiest(world, name) for name in ("O5", "O7", "O4")]
    waypoints = grid_path(world.clearance, world.grid, [tuple(start[:2]), *rooms], 0.5)
    length = sum(math.dist(a, b) for a, b in itertools.pairwise(waypoints))
    lidar = Lidar(world.grid, sensor)
    runs = [
        drive(world.grid, lidar, waypoints, start, AmclParams(), models.motion_noise, models.dt, robot.speed, s)
        for s in SEEDS
    ]
    err = np.concatenate([np.hypot(*np.array(r.errors).T) for r in runs])
    std = np.concatenate([np.array(r.stds) for r in runs])
    e_axis = np.concatenate([np.array(r.errors) for r in runs])
    updates, seconds = sum(r.updates for r in runs), sum(r.seconds for r in runs)
    return [
        f"(a) office-ros, r1 from its start through O5, O7, O4: {length:.1f} m, {len(runs)} runs, {err.size} "
        f"control steps of {models.dt:g} s at {robot.speed:g} m/s, motion noise alpha1-4 {models.motion_noise}",
        f"    position error  median {np.median(err):.3f} m, p90 {np.percentile(err, 90):.3f} m, max {err.max():.3f} m",
        f"    RMS error per axis {rms(e_axis):.3f} m; reported std per axis: median {np.median(std):.3f} m, "
        f"p90 {np.percentile(std, 90):.3f} m",
        f"    filter updates {updates} ({updates / len(runs):.0f} per run), {1000 * seconds / updates:.0f} ms each",
    ]


def corridor_grid(length: float, width: float, res: float = 0.05) -> OccupancyGrid:
    wall = 3
    rows, cols = round(width / res) + 2 * wall, round(length / res) + 2 * wall
    occupied = np.zeros((rows, cols), dtype=bool)
    occupied[:wall], occupied[-wall:], occupied[:, :wall], occupied[:, -wall:] = True, True, True, True
    return OccupancyGrid(occupied, (-wall * res, -wall * res), res)


LIDAR = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01)
ALPHAS, DT, SPEED = (0.01, 0.0, 0.02, 0.01), 0.5, 0.5


def corridor() -> list[str]:
    grid = corridor_grid(30.0, 2.0)
    lidar = Lidar(grid, LIDAR)
    waypoints = [(x, 1.0) for x in np.arange(2.0, 28.01, 1.0)]
    lines = [f"(b) corridor 30 m x 2 m, no feature, x from 1.5 to 28 m at {SPEED:g} m/s, {len(SEEDS)} runs each"]
    for alphas in (0.2, 0.05):
        params = replace(AmclParams(), alpha1=alphas, alpha2=alphas, alpha3=alphas, alpha4=alphas)
        runs = [drive(grid, lidar, waypoints, (1.5, 1.0, 0.0), params, ALPHAS, DT, SPEED, s) for s in SEEDS]
        x = np.concatenate([np.array(r.truth)[:, 0] for r in runs])
        e = np.concatenate([np.array(r.errors) for r in runs])
        s = np.concatenate([np.array(r.stds) for r in runs])
        lines.append(f"  AMCL's alpha1-4 {alphas:g}{' (nav2 default)' if alphas == 0.2 else ''}:")
        regions = (("start, x < 12", x <= 12), ("middle, 12 < x < 18", (x > 12) & (x < 18)), ("end, x > 18", x >= 18))
        for label, at in regions:
            lines.append(
                f"    {label:<20} along: mean error {e[at, 0].mean():+.3f} m, RMS {rms(e[at, 0]):.3f} m, "
                f"median std {np.median(s[at, 0]):.3f} m | across: RMS error {rms(e[at, 1]):.3f} m, "
                f"max {np.abs(e[at, 1]).max():.3f} m, median std {np.median(s[at, 1]):.3f} m"
            )
    return lines


def thresholds() -> list[str]:
    grid = corridor_grid(30.0, 30.0)
    # the counts do not depend on the particles: few of them keep this part quick
    lidar, rng = Lidar(grid, LIDAR), np.random.default_rng(0)
    params = replace(AmclParams(), min_particles=100, max_particles=200)
    lines = [
        f"(c) update thresholds (update_min_d {params.update_min_d} m, update_min_a {params.update_min_a} rad), "
        f"in a 30 m x 30 m room, {params.min_particles}-{params.max_particles} particles"
    ]
    cases = [
        ("20 m straight along x, 0.04 m steps", [(0.04, 0.0, 0.0)] * 500),
        ("20 m straight at 45 deg, 0.04 m steps", [(0.04 / math.sqrt(2), 0.04 / math.sqrt(2), 0.0)] * 500),
        ("turn in place 2 pi, 0.05 rad steps", [(0.0, 0.0, 0.05)] * round(2 * math.pi / 0.05)),
        ("standing still, 50 scans", [(0.0, 0.0, 0.0)] * 50),
    ]
    for label, steps in cases:
        start = np.array([5.0, 5.0, math.pi / 4 if "45" in label else 0.0])
        loc = AmclLocaliser(grid, LIDAR, params, start, np.diag([0.01, 0.01, 0.0025]), seed=1)
        odom, count = start.copy(), 0
        for d in steps:
            odom = odom + np.array(d)
            count += loc.update(odom, lidar.ranges(odom, rng))
        lines.append(f"    {label:<40} {count:>3} filter updates (the first scan included)")
    amcl = bindings()
    raw = amcl.AMCL(100, 200, 0.0, 0.0, amcl.MotionParameters(*[0.2] * 5),
                    amcl.LaserParameters(0.5, 0.05, 0.05, 0.5, 0.2, 0.1, 0.0, 60), "differential")  # fmt: skip
    x0, y0 = (o + grid.resolution / 2 for o in grid.origin)  # cell centres where tmpnav has them (part d)
    raw.set_map(amcl.create_occupancy_grid_from_list(np.where(grid.occupied, 100, 0).tolist(), grid.resolution, x0, y0))
    raw.set_initial_pose(amcl.Vector3D(5.0, 5.0, 0.0), amcl.create_diagonal_covariance(0.01, 0.01, 0.0025))
    pose, stds = np.array([5.0, 5.0, 0.0]), []
    for _ in range(50):
        r = lidar.ranges(pose, rng)
        r = np.where(np.isnan(r), LIDAR.range, r)
        raw.update(amcl.create_laser_scan_from_list(np.column_stack([r, lidar.angles]).tolist(), LIDAR.range),
                   amcl.Vector3D(*pose))  # fmt: skip
        stds.append(math.sqrt(np.array(raw.get_pose_covariance().to_list())[0, 0]))
    lines.append(
        f"    the bindings called directly, standing still: x std {stds[0]:.3f} m after 1 scan, "
        f"{stds[9]:.3f} m after 10, {stds[-1]:.3f} m after 50 (every call updates and resamples)"
    )
    return lines


def half_cell() -> list[str]:
    res = 0.2
    grid = corridor_grid(10.0, 6.0, res)
    occupied = grid.occupied.copy()
    occupied[12:20, 20:25] = True  # a pillar and a wall stub: the room has no symmetry
    occupied[5:8, 35:] = True
    grid = OccupancyGrid(occupied, grid.origin, res)
    truth, sensor = np.array([2.3, 1.7, 0.3]), replace(LIDAR, beams=360)
    lidar = Lidar(grid, sensor)
    lines = [f"(d) standing at (2.3, 1.7) on a {res} m grid, 360 beams, 30 forced updates, {len(SEEDS)} seeds"]
    for label, origin in (("cells where tmpnav has them", grid.origin), ("origin read as nav2 reads it", None)):
        bias = []
        for seed in SEEDS:
            rng = np.random.default_rng(seed)
            shifted = (
                grid
                if origin is not None
                else replace(grid, origin=(grid.origin[0] - res / 2, grid.origin[1] - res / 2))
            )
            params = replace(AmclParams(), update_min_d=0.0, update_min_a=0.0)
            loc = AmclLocaliser(shifted, sensor, params, truth, np.diag([0.04, 0.04, 0.01]), seed=seed)
            for k in range(30):
                odom = truth + np.array([1e-6 * (k % 2), 0.0, 0.0])  # a hair of motion: past the zero thresholds
                loc.update(odom, lidar.ranges(truth, rng))
            bias.append(loc.mean[:2] - truth[:2])
        b = np.mean(bias, axis=0)
        lines.append(f"    {label:<30} mean error (x, y) ({b[0]:+.3f}, {b[1]:+.3f}) m")
    return lines


def main() -> None:
    t0 = time.perf_counter()
    lines = ["AMCL bindings (amcl 0.1.2) through tmpnav.execution.amcl, nav2's default parameters", ""]
    for part in (office, corridor, thresholds, half_cell):
        lines += [*part(), ""]
        print(f"{part.__name__} done, {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    lines.append(f"{time.perf_counter() - t0:.0f} s in all")
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
