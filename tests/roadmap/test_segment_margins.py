"""The least clearance along segments (tmpnav.roadmap.graph._least_clearance), which skips the
points of a cell it has read, against every point read one by one."""

from __future__ import annotations

import numpy as np

from tmpnav.roadmap.graph import _least_clearance


def every_point(
    a: np.ndarray, b: np.ndarray, s: np.ndarray, x0: float, y0: float, res: float, clear: np.ndarray
) -> np.ndarray:
    """The least clearance of the cells of all the points a[k] + s (b[k] - a[k]), -inf off the grid."""
    rows, cols = clear.shape
    d = b - a
    j = np.floor(((a[:, :1] + s[None, :] * d[:, :1]) - x0) / res)
    i = np.floor(((a[:, 1:] + s[None, :] * d[:, 1:]) - y0) / res)
    off = (i < 0) | (i >= rows) | (j < 0) | (j >= cols)
    c = clear[np.clip(i, 0, rows - 1).astype(int), np.clip(j, 0, cols - 1).astype(int)]
    return np.where(off.any(axis=1), -np.inf, c.min(axis=1))


def test_skipping_a_cells_points_finds_the_least_clearance_of_every_point() -> None:
    rng = np.random.default_rng(7)
    res, x0, y0 = 0.05, -1.3, 0.7
    clear = rng.uniform(0.0, 2.0, (120, 160))
    n = 3000
    a = rng.uniform([x0 - 0.5, y0 - 0.5], [x0 + 8.5, y0 + 6.5], (n, 2))
    # long, short, tiny and zero-length segments, some leaving the grid
    b = a + rng.normal(0.0, 1.0, (n, 2)) * rng.choice([0.0, 1e-3, 0.05, 0.5, 3.0], (n, 1))
    for longest in (2, 40, 700):
        s = np.linspace(0.0, 1.0, longest)
        found = _least_clearance(a, b, s, x0, y0, res, clear)
        assert found.tobytes() == every_point(a, b, s, x0, y0, res, clear).tobytes()
