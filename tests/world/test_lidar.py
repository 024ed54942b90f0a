"""The range sensor's geometry (tmpnav/world/lidar.py): ray casting, beam Jacobians, scan information."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.models import beam_jacobian, beam_variance, compressed_scan, scan_information
from tmpnav.pipeline import load_world
from tmpnav.shipped import configs_dir
from tmpnav.types import RangeSensor
from tmpnav.world import World
from tmpnav.world.grid import OccupancyGrid, among
from tmpnav.world.lidar import cast, scan, sensor_params, signed_distance
from tmpnav.world.scan_information import ScanInformation, information_matrices

LIDAR = RangeSensor(
    range=12.0,
    fov=2 * math.pi,
    beams=60,
    sigma_range=0.03,
    min_range=0.1,
    max_incidence=math.radians(75),
    divergence=0.01,
)


def box(rows: int = 120, cols: int = 200, res: float = 0.05) -> OccupancyGrid:
    """A 10 m x 6 m room with walls three cells thick and a pillar."""
    occupied = np.zeros((rows, cols), dtype=bool)
    occupied[:3], occupied[-3:], occupied[:, :3], occupied[:, -3:] = True, True, True, True
    occupied[50:70, 90:110] = True
    return OccupancyGrid(occupied, (0.0, 0.0), res)


def _scan(sdf: np.ndarray, grid: OccupancyGrid, pose: np.ndarray, sensor: RangeSensor = LIDAR, variances=False):  # type: ignore[no-untyped-def]
    r, H, var = np.empty(sensor.beams), np.empty((sensor.beams, 3)), np.empty(sensor.beams)
    scan(sdf, *grid.origin, grid.resolution, pose, sensor.beam_angles(), sensor_params(sensor), r, H, var)
    return (r, H, var) if variances else (r, H)


def test_the_field_changes_sign_on_the_boundary_between_free_and_occupied_cells() -> None:
    grid = box()
    sdf = signed_distance(grid)
    assert (sdf[grid.occupied] < 0).all() and (sdf[~grid.occupied] > 0).all()
    # next to the wall the field is half a cell on either side: its zero is the cells' boundary
    assert sdf[30, 3] == pytest.approx(0.025) and sdf[30, 2] == pytest.approx(-0.025)


def test_a_beam_meets_the_wall_on_the_cells_boundary() -> None:
    """From (2, 1.5) the inner faces of the walls are at x = 0.15 and x = 9.85, y = 0.15 and 5.85."""
    grid = box()
    sdf = signed_distance(grid)
    expected = {0.0: 9.85 - 2.0, math.pi: 2.0 - 0.15, math.pi / 2: 5.85 - 1.5, -math.pi / 2: 1.5 - 0.15}
    for psi, distance in expected.items():
        r, gx, gy = cast(sdf, 0.0, 0.0, 0.05, 2.0, 1.5, psi, 12.0)
        assert r == pytest.approx(distance, abs=1e-3)
        assert math.hypot(gx, gy) > 0
    assert cast(sdf, 0.0, 0.0, 0.05, 2.0, 3.0, 0.0, 12.0)[0] == pytest.approx(4.5 - 2.0, abs=1e-3)  # the pillar
    assert math.isinf(cast(sdf, 0.0, 0.0, 0.05, 2.0, 1.5, 0.0, 5.0)[0])  # beyond the range
    assert math.isnan(cast(sdf, 0.0, 0.0, 0.05, 0.05, 0.05, 0.0, 5.0)[0])  # from inside a wall


def _finite_difference_jacobian(sdf: np.ndarray, grid: OccupancyGrid, pose: np.ndarray, h: float = 1e-5):
    H = np.zeros((LIDAR.beams, 3))
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        plus, _ = _scan(sdf, grid, pose + step)
        minus, _ = _scan(sdf, grid, pose - step)
        H[:, k] = (plus - minus) / (2 * h)
    return H


def test_each_beams_jacobian_is_the_derivative_of_its_range() -> None:
    grid = box()
    sdf = signed_distance(grid)
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(20):
        pose = np.array([rng.uniform(0.6, 9.4), rng.uniform(0.6, 5.4), rng.uniform(-math.pi, math.pi)])
        if grid.is_occupied(pose[None, :2])[0] or sdf[int(pose[1] / 0.05), int(pose[0] / 0.05)] < 0.3:
            continue
        r, H = _scan(sdf, grid, pose)
        fd = _finite_difference_jacobian(sdf, grid, pose)
        ok = ~np.isnan(r) & np.isfinite(fd).all(axis=1)
        # a beam whose finite difference crosses an edge (the pillar's corner) jumps: leave it out
        smooth = np.abs(fd - H).max(axis=1) < 1e-3 * (1 + np.abs(H).max(axis=1))
        assert smooth[ok].mean() > 0.9
        checked += int((ok & smooth).sum())
    assert checked > 500


def test_the_compiled_beam_row_is_the_model_equation() -> None:
    """tmpnav.world.lidar's Jacobian (compiled) against tmpnav.belief.models.beam_jacobian (the equation)."""
    rng = np.random.default_rng(1)
    r = rng.uniform(0.2, 10.0, 200)
    psi = rng.uniform(-math.pi, math.pi, 200)
    alpha = psi + rng.uniform(-1.2, 1.2, 200)  # the normal into the wall, within 69 deg of the beam
    g = -np.stack([np.cos(alpha), np.sin(alpha)], axis=1) * rng.uniform(0.5, 2.0, (200, 1))
    H = beam_jacobian(r, g, psi)
    beta = alpha - psi
    censi = -np.stack([np.cos(alpha), np.sin(alpha), r * np.sin(beta)], axis=1) / np.cos(beta)[:, None]
    np.testing.assert_allclose(H, censi, rtol=1e-12, atol=1e-12)


def _censi_information(sdf: np.ndarray, grid: OccupancyGrid, pose: np.ndarray) -> np.ndarray:
    """Censi's closed form: sum over the returning beams of u uᵀ / sigma_i², u = [v(alpha); r sin(beta)] /
    cos(beta), alpha the angle of the surface normal into the wall, beta the incidence and sigma_i²
    the beam's variance (tmpnav.belief.models.beam_variance)."""
    J = np.zeros((3, 3))
    for phi in LIDAR.beam_angles():
        psi = pose[2] + phi
        r, gx, gy = cast(sdf, *grid.origin, grid.resolution, pose[0], pose[1], psi, LIDAR.range)
        if not (r >= LIDAR.min_range and math.isfinite(r)):
            continue
        alpha = math.atan2(-gy, -gx)
        beta = math.remainder(alpha - psi, 2 * math.pi)
        if abs(beta) > LIDAR.max_incidence:
            continue
        u = np.array([math.cos(alpha), math.sin(alpha), r * math.sin(beta)]) / math.cos(beta)
        J += np.outer(u, u) / beam_variance(LIDAR.sigma_range, LIDAR.divergence, r, beta)
    return J


@pytest.mark.parametrize("config", ["building-20.yaml", "office-ros.yaml"])
def test_jacobian_information_matches_censis_closed_form(config: str) -> None:
    """At 100 random free poses of a polygonal and a ROS map, the information from the beams'
    finite-difference Jacobians (sum Hᵀ H / sigma²) agrees with Censi's closed form within 5%,
    entry by entry relative to the diagonal (|dJ_ij| <= 0.05 sqrt(J_ii J_jj))."""
    _, world = load_world(configs_dir() / config)
    grid, sdf = world.grid, world.signed_distance
    rng = np.random.default_rng(11)
    x0, y0, x1, y1 = grid.extent
    poses, agree = 0, 0
    while poses < 100:
        pose = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1), rng.uniform(-math.pi, math.pi)])
        i, j, inside = grid.cells(pose[None, :2])
        if not inside[0] or world.clearance[i[0], j[0]] < 0.3:
            continue
        censi = _censi_information(sdf, grid, pose)
        r, _, var = _scan(sdf, grid, pose, variances=True)
        fd = _finite_difference_jacobian(sdf, grid, pose)
        fd[np.isnan(r)] = 0.0
        jac = scan_information(fd, np.sqrt(np.where(np.isnan(r), 1.0, var)))
        scale = np.sqrt(np.outer(np.diag(censi), np.diag(censi)))
        poses += 1
        agree += bool((np.abs(jac - censi) <= 0.05 * scale + 1e-9).all())
    assert agree >= 95, f"{agree} of {poses} poses agree within 5%"


def test_the_information_table_is_the_information_at_the_cell_centre() -> None:
    grid = box()
    sdf = signed_distance(grid)
    limited = RangeSensor(8.0, math.radians(270), 40, 0.02, 0.1, math.radians(70))
    table = ScanInformation(grid, sdf, limited)
    poses = np.array([[2.02, 3.01, 0.1], [2.02, 3.01, 1.7], [7.5, 1.2, -2.0], [-1.0, 1.0, 0.0]])
    keys = table.keys(poses)
    assert keys[0] != keys[1] and keys[-1] < 0
    rows = table.rows(keys)
    assert rows[-1] == 0 and (table.table[0] == 0).all()
    np.testing.assert_array_equal(table.rows(keys), rows)  # the same rows the second time
    for pose, row in zip(poses[:3], rows[:3], strict=True):
        i, j, _ = grid.cells(pose[None, :2])
        centre = np.array(
            [(j[0] + 0.5) * 0.05, (i[0] + 0.5) * 0.05, round(pose[2] / (2 * math.pi / 72)) * 2 * math.pi / 72]
        )
        G = table.table[row]
        np.testing.assert_allclose(G.T @ G, information_matrices(sdf, grid, limited, centre[None])[0], rtol=1e-9)
    assert ScanInformation(grid, sdf, LIDAR).bins == 1  # all round: the heading does not matter


def test_the_compressed_scan_is_the_update_with_every_beam() -> None:
    """The EKF's posterior with B beams equals the one with the 3-D pseudo-measurement of
    compressed_scan: same covariance, same mean."""
    rng = np.random.default_rng(4)
    H = rng.normal(0, 1, (40, 3)) * [1.0, 1.0, 3.0]
    H[:, 0] = 0.0  # a corridor: nothing along x
    y = rng.normal(0, 0.03, 40)
    sigma = 0.03
    A = rng.normal(0, 0.1, (3, 3))
    P = A @ A.T + 1e-3 * np.eye(3)
    S = H @ P @ H.T + sigma**2 * np.eye(40)
    K = P @ H.T @ np.linalg.inv(S)
    full_mean, full_cov = K @ y, P - K @ H @ P
    G, y_G = compressed_scan(H, y, sigma)
    S3 = G @ P @ G.T + np.eye(3)
    K3 = P @ G.T @ np.linalg.inv(S3)
    np.testing.assert_allclose(K3 @ y_G, full_mean, atol=1e-12)
    np.testing.assert_allclose(P - K3 @ G @ P, full_cov, atol=1e-12)
    assert np.allclose(G[np.abs(G).sum(axis=1) > 0][:, 0], 0.0)  # no row sees along x


def world_of(grid: OccupancyGrid) -> World:
    """A World of a bare grid (no rooms, no landmarks), for the tests that need one."""
    from tmpnav.world.grid import clearance

    return World(grid, clearance(grid), (), (), np.zeros((0, 2)), "test")


def test_a_poses_key_is_its_cell_and_nearest_heading_bin() -> None:
    """ScanInformation.keys (compiled) against the grid's cells and the bin arithmetic written out,
    on poses off the grid, on cell edges and with headings of any sign and size."""
    grid = box()
    sdf = signed_distance(grid)
    rng = np.random.default_rng(3)
    poses = np.column_stack([rng.uniform(-1.0, 11.0, 500), rng.uniform(-1.0, 7.0, 500), rng.uniform(-20, 20, 500)])
    edges = np.array([[0.0, 0.0, 0.0], [0.05, 0.1, -math.pi], [9.999, 5.999, 2 * math.pi], [10.0, 3.0, 1e-12]])
    poses = np.concatenate([poses, edges])
    for sensor in (LIDAR, RangeSensor(8.0, math.radians(270), 40, 0.02, 0.1, math.radians(70))):
        table = ScanInformation(grid, sdf, sensor)
        i, j, inside = grid.cells(poses[:, :2])
        b = np.floor(np.mod(poses[:, 2], 2 * math.pi) * (table.bins / (2 * math.pi)) + 0.5).astype(np.int64)
        expected = np.where(inside, (i * grid.shape[1] + j) * table.bins + b % table.bins, -1)
        np.testing.assert_array_equal(table.keys(poses), expected)
        assert table.keys(poses.reshape(2, -1, 3)).shape == (2, poses.shape[0] // 2)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.integers(0, 60), max_size=40), st.lists(st.integers(0, 60), max_size=40))
def test_a_key_is_known_by_binary_search_as_isin_says(keys: list[int], known: list[int]) -> None:
    table = np.unique(np.array(known, dtype=np.int64))
    wanted = np.array(keys, dtype=np.int64)
    assert among(wanted, table).tolist() == np.isin(wanted, table).tolist()


@pytest.mark.parametrize("blur", [0.0, 0.05, 0.2])
def test_the_likelihood_fields_information_weighs_each_beam_by_its_endpoints_spread(blur: float) -> None:
    """nav2's AMCL model: each returning beam of the ``max_beams`` AMCL weighs informs the pose by
    H_i^T H_i kappa eta / ((sigma_lf² + r_i² heading_blur²)(h0² + h1²)) (docs/models.md, "What
    a localiser achieves"): the particle cloud's heading spread spreads a far endpoint more than
    a near one. Checked beam by beam against the ray cast, with and without the blur."""
    from dataclasses import replace as replaced

    from tmpnav.types import NAV2_AMCL
    from tmpnav.world.lidar import localiser_angles

    grid = box()
    sdf = signed_distance(grid)
    sensor = replaced(LIDAR, beams=120, localiser=replaced(NAV2_AMCL, heading_blur=blur, floor_beams=0.0))
    pose = np.array([2.3, 1.7, 0.4])
    angles = localiser_angles(sensor)
    r, H, var = np.empty(angles.size), np.empty((angles.size, 3)), np.empty(angles.size)
    params = sensor_params(sensor, grid.resolution)
    scan(sdf, *grid.origin, grid.resolution, pose, angles, params, r, H, var)
    ok = np.isfinite(r)
    assert ok.sum() > 10 and r[ok].max() > 4 * r[ok].min()  # near and far walls, the pillar
    weight = params[7] / ((params[6] + r[ok] ** 2 * blur**2) * (H[ok, 0] ** 2 + H[ok, 1] ** 2))
    expected = (H[ok, :, None] * H[ok, None, :] * weight[:, None, None]).sum(axis=0)
    np.testing.assert_allclose(information_matrices(sdf, grid, sensor, pose[None])[0], expected, rtol=1e-9)
    assert params[8] == pytest.approx(blur**2)


@pytest.mark.parametrize("floor", [0.0, 5.0, 15.0, 40.0])
def test_each_direction_of_a_scan_loses_the_information_of_floor_beams_head_on_beams(floor: float) -> None:
    """AMCL's model with ``floor_beams`` n_f: J = kappa sum_k max(lambda_k - n_f eta / sigma_lf², 0)
    e_k e_kᵀ over the eigenpairs of the likelihood field's J (docs/models.md, "Directions AMCL does
    not resolve"): a direction with less than the floor tells nothing, the others keep their excess."""
    from dataclasses import replace as replaced

    from tmpnav.types import NAV2_AMCL

    grid = box()
    sdf = signed_distance(grid)
    pose = np.array([[2.3, 1.7, 0.4]])
    full = information_matrices(sdf, grid, replaced(LIDAR, localiser=replaced(NAV2_AMCL, floor_beams=0.0)), pose)[0]
    sensor = replaced(LIDAR, localiser=replaced(NAV2_AMCL, floor_beams=floor))
    params = sensor_params(sensor, grid.resolution)
    one_beam = params[7] / params[6]  # kappa eta / sigma_lf²: one head-on beam's information
    assert params[9] == pytest.approx(floor * one_beam)
    lam, vec = np.linalg.eigh(full)
    kept = np.clip(lam - floor * one_beam, 0.0, None)
    expected = (vec * kept) @ vec.T
    np.testing.assert_allclose(information_matrices(sdf, grid, sensor, pose)[0], expected, atol=1e-9 * lam.max())
    if floor == 40.0:
        assert (lam < floor * one_beam).any()  # some direction lost all it had
