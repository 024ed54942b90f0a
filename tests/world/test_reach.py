"""Sector reach (tmpnav/world/reach.py): no point of a sector closer than its reach hits a wall."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.belief.test_risk import PATHS, RADIUS
from tmpnav.belief import risk
from tmpnav.world.grid import clearance
from tmpnav.world.reach import OFF_GRID, REACH, SECTORS, SectorReach


@pytest.mark.parametrize("case", ["straight", "corner"])
def test_no_point_of_a_sector_within_its_reach_hits_a_wall(case: str) -> None:
    """The lemma behind the directional bound, at random positions of each map: points of sector
    k (direction in [k w, (k+1) w)) closer than R_k to mu never hit a wall; R_k is reached or the cap."""
    grid, _ = PATHS[case]
    clear = clearance(grid)
    table = SectorReach(grid, clear, RADIUS)
    rng = np.random.default_rng(5)
    mu = rng.uniform((0.0, 0.0), grid.extent[2:], (4000, 2))
    everywhere = table.at(mu)
    mu = mu[~risk.hits_wall(grid, clear, mu, RADIUS)]  # a position that hits has reach 0 all round
    reach = table.at(mu)  # (N, K)
    w = 2 * math.pi / SECTORS
    k = rng.integers(0, SECTORS, (mu.shape[0], 48))
    angle = (k + rng.uniform(0.0, 1.0, k.shape)) * w
    dist = np.take_along_axis(reach, k, axis=1) * np.sqrt(rng.uniform(0.0, 1.0, k.shape)) * 0.999999
    x = mu[:, None, :] + dist[..., None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    assert not risk.hits_wall(grid, clear, x, RADIUS).any()
    assert (reach <= REACH).all() and (reach > 0).any() and (everywhere == 0).all(axis=1).any()


def test_reach_is_zero_on_a_wall_and_off_the_grid_and_within_the_old_margin_at_least() -> None:
    grid, _ = PATHS["straight"]
    clear = clearance(grid)
    table = SectorReach(grid, clear, RADIUS)
    mu = np.array([[3.01, 0.51], [-1.0, 0.5], [3.0, 1.55], [3.0, 0.8]])  # free, off the grid, a wall, the middle
    assert table.cells(mu)[1] == OFF_GRID
    reach = table.at(mu)
    assert (reach[1] == 0).all() and (reach[2] == 0).all()
    margin = risk.margins(grid, mu[[0, 3]], RADIUS, clear)
    assert (reach[[0, 3]].min(axis=1) >= margin - 1e-9).all()  # never below the disc's margin
    assert reach[3, 0] > reach[3].min()  # along the corridor it reaches farther than across it


def test_cells_are_computed_once_and_remembered() -> None:
    grid, _ = PATHS["corner"]
    table = SectorReach(grid, clearance(grid), RADIUS)
    pts = np.array([[0.5, 0.5], [0.51, 0.52], [2.9, 3.0]])
    first = table.at(pts)
    rows = table.rows
    assert rows == 1 + 2  # row 0 is off the grid; the first two points share a cell
    assert np.array_equal(table.at(pts[::-1]), first[::-1]) and table.rows == rows


def test_a_table_grown_in_blocks_and_learned_out_of_order_reads_as_one_asked_at_once() -> None:
    """Keys merged into the sorted ones block by block (computed here, or learned from another
    copy in any order) give every point the reach of a table that computed them all at once."""
    grid, _ = PATHS["corner"]
    rng = np.random.default_rng(3)
    x0, y0 = grid.origin
    pts = np.column_stack(
        [rng.uniform(x0 - 0.5, grid.extent[2] + 0.5, 400), rng.uniform(y0 - 0.5, grid.extent[3] + 0.5, 400)]
    )
    whole = SectorReach(grid, clearance(grid), RADIUS).at(pts)
    worker = SectorReach(grid, clearance(grid), RADIUS)
    worker.take_new()
    blocks = [worker.at(pts[k : k + 37]) for k in range(0, len(pts), 37)]
    assert np.array_equal(np.concatenate(blocks), whole)
    keys, codes = worker.take_new()
    order = rng.permutation(keys.size)
    parent = SectorReach(grid, clearance(grid), RADIUS)
    parent.at(pts[::5])  # some known already
    for part in np.array_split(order, 4):
        parent.learn(keys[part], codes[part])
    assert np.array_equal(parent.at(pts), whole) and np.all(np.diff(parent.keys) > 0)


def test_only_a_table_asked_once_for_its_new_cells_records_them() -> None:
    """The planning process never asks (take_new): it keeps no record; a worker's copy asks when
    it starts, then hands back what it computed since, and another copy learns it."""
    grid, _ = PATHS["corner"]
    table = SectorReach(grid, clearance(grid), RADIUS)
    table.at(np.array([[0.5, 0.5]]))
    assert table._new is None  # the planning process's table records nothing
    assert table.take_new()[0].size == 0  # the record starts
    pts = np.array([[2.9, 3.0], [1.5, 0.5]])
    first = table.at(pts)
    keys, reach = table.take_new()
    assert keys.size == 2 and table.take_new()[0].size == 0
    other = SectorReach(grid, clearance(grid), RADIUS)
    other.learn(keys, reach)
    assert np.array_equal(other.at(pts), first) and other.rows == 3 and other._new is None


def test_a_points_key_is_its_sub_cell() -> None:
    """SectorReach.cells (compiled) against the sub-cell arithmetic written out, off the grid too."""
    grid, _ = PATHS["corner"]
    table = SectorReach(grid, clearance(grid), RADIUS)
    rng = np.random.default_rng(5)
    lo, hi = np.array(grid.origin) - 1.0, np.array(grid.origin) + np.array(grid.shape[::-1]) * grid.resolution + 1.0
    pts = np.concatenate([rng.uniform(lo, hi, (500, 2)), np.array([grid.origin]), [hi - 1.0]])
    size = grid.resolution / table.subdivisions
    col = np.floor((pts[:, 0] - grid.origin[0]) / size).astype(np.int64)
    row = np.floor((pts[:, 1] - grid.origin[1]) / size).astype(np.int64)
    rows, cols = grid.shape[0] * table.subdivisions, grid.shape[1] * table.subdivisions
    inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
    np.testing.assert_array_equal(table.cells(pts), np.where(inside, row * cols + col, OFF_GRID))
    assert table.cells(pts[:4].reshape(2, 2, 2)).shape == (2, 2)


def plain_reach(table: SectorReach, key: int) -> np.ndarray:
    """The module docstring's construction written plainly for one sub-cell: every boundary hit
    cell within the cap, its square's distance and the sectors between its corners' bearings."""
    res, s = table.grid.resolution, table.subdivisions
    cols = table.grid.shape[1] * s
    si, sj = divmod(key, cols)
    i0, j0 = si // s + 1, sj // s + 1
    oy = ((si % s) + 0.5) * res / s - 0.5 * res
    ox = ((sj % s) + 0.5) * res / s - 0.5 * res
    half, w = 0.5 * res * (1.0 + 1.0 / s), 2.0 * math.pi / SECTORS
    out = np.full(SECTORS, REACH)
    if table.hit[i0, j0]:
        return np.zeros(SECTORS)
    for i, j in zip(*np.nonzero(table.boundary), strict=True):
        dy, dx = (i - i0) * res - oy, (j - j0) * res - ox
        d = math.hypot(max(abs(dx) - half, 0.0), max(abs(dy) - half, 0.0))
        if d >= REACH:
            continue
        if d <= 0.0:
            out[:] = 0.0
            continue
        phi = math.atan2(dy, dx)
        turns = [math.atan2(dy + sy, dx + sx) - phi for sx in (-half, half) for sy in (-half, half)]
        turns = [t - 2 * math.pi if t > math.pi else t + 2 * math.pi if t < -math.pi else t for t in turns]
        for k in range(math.floor((phi + min(0.0, *turns)) / w), math.floor((phi + max(0.0, *turns)) / w) + 1):
            out[k % SECTORS] = min(out[k % SECTORS], d)
    return out


@pytest.mark.parametrize("case", ["straight", "corner"])
def test_the_table_is_the_construction_written_plainly(case: str) -> None:
    grid, _ = PATHS[case]
    table = SectorReach(grid, clearance(grid), RADIUS)
    rng = np.random.default_rng(11)
    keys = np.unique(table.cells(rng.uniform((0.0, 0.0), grid.extent[2:], (60, 2))))
    keys = keys[keys != OFF_GRID]
    computed = table.of_cells(keys)
    for key, row in zip(keys, computed, strict=True):
        assert np.allclose(row, plain_reach(table, int(key)), rtol=0.0, atol=1e-12)


def test_the_table_keeps_codes_of_the_floats_computed_two_bytes_a_sector() -> None:
    """Each sector is a uint16 code into the distinct reaches there can be, and reads back as the
    float the construction gives, bit for bit: the offsets' distances, 0 and the cap."""
    from tmpnav.world.reach import _offsets, encoded

    grid, _ = PATHS["corner"]
    table = SectorReach(grid, clearance(grid), RADIUS)
    rng = np.random.default_rng(3)
    reach = table.at(rng.uniform((0.0, 0.0), grid.extent[2:], (400, 2)))
    assert table.codes.dtype == np.uint16 and table.codes.nbytes == table.codes.shape[0] * SECTORS * 2
    _, _, dist, _, _, count = _offsets(grid.resolution, table.subdivisions, REACH, SECTORS)
    offered = {0.0, REACH} | {float(d) for q in range(count.size) for d in dist[q, : count[q]] if d > 0.0}
    assert set(np.unique(reach).tolist()) <= offered and set(table.values.tolist()) == offered
    assert (reach == 0).any() and (reach == REACH).any() and ((reach > 0) & (reach < REACH)).any()
    codes, values = encoded(reach)  # any array of reaches, in the kernels' form
    assert np.array_equal(values[codes], reach) and codes.dtype == np.uint16
