"""Planar geometry (world/geometry.py): the angle-wrapping rule, in numpy and compiled, and the even-odd rule."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.world.geometry import points_in_polygon, wrap_angle, wrap_angle_scalar

EDGES = [
    math.pi,
    -math.pi,
    3 * math.pi,
    -3 * math.pi,
    0.5,
    2 * math.pi + 0.5,
    -math.pi - 1e-17,
    math.nextafter(-math.pi, -4),
]


def test_wrap_angle_range_and_edges() -> None:
    w = wrap_angle(np.array(EDGES))
    assert np.all(w >= -np.pi) and np.all(w < np.pi)
    np.testing.assert_allclose(w[:4], -np.pi)
    np.testing.assert_allclose(w[5], 0.5)


@given(st.floats(-100.0, 100.0))
def test_wrap_angle_is_idempotent_and_preserves_the_angle(a: float) -> None:
    w = wrap_angle(a)
    assert -np.pi <= w < np.pi
    assert wrap_angle(w) == w  # bit for bit
    assert np.isclose(np.cos(w), np.cos(a), atol=1e-9) and np.isclose(np.sin(w), np.sin(a), atol=1e-9)


@settings(deadline=None)  # the first example loads (or compiles) the numba function: 0.25 s on a busy machine
@given(st.floats(-1e6, 1e6) | st.sampled_from(EDGES))
def test_the_compiled_twin_gives_the_same_bits(a: float) -> None:
    assert wrap_angle_scalar(a) == float(wrap_angle(a))
    assert math.copysign(1.0, wrap_angle_scalar(a)) == math.copysign(1.0, float(wrap_angle(a)))


def test_angles_in_range_pass_through_unchanged() -> None:
    inside = np.array([-math.pi, -1.0, 0.0, 1e-300, math.nextafter(math.pi, 0.0)])
    assert np.array_equal(wrap_angle(inside), inside)
    assert [wrap_angle_scalar(float(a)) for a in inside] == inside.tolist()


def _even_odd_broadcast(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """The even-odd rule in numpy's broadcast form: what the compiled loop must give, point for point."""
    px, py = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0 = polygon[:, 0][None, :], polygon[:, 1][None, :]
    x1, y1 = np.roll(polygon[:, 0], -1)[None, :], np.roll(polygon[:, 1], -1)[None, :]
    straddles = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    return np.count_nonzero(straddles & (px < x_cross), axis=1) % 2 == 1


def test_points_in_polygon_agree_with_the_broadcast_rule_on_vertices_and_edges() -> None:
    """Random polygons on a 0.1 m lattice, probed at random points, at their vertices and at their
    edges' midpoints: the points a grid's cell centres put on a room's outline."""
    rng = np.random.default_rng(3)
    for _ in range(500):
        polygon = np.round(rng.uniform(0.0, 5.0, (int(rng.integers(3, 9)), 2)), 1)
        points = np.concatenate(
            [np.round(rng.uniform(-0.5, 5.5, (100, 2)), 2), polygon, (polygon + np.roll(polygon, -1, axis=0)) / 2]
        )
        assert (points_in_polygon(points, polygon) == _even_odd_broadcast(points, polygon)).all()
