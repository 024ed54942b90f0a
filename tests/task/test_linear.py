"""The linear-program adapter (tmpnav.task.linear): solutions, duals as the bound reads them."""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix

from tmpnav.task.linear import minimise


def test_an_lp_with_its_solution_and_duals() -> None:
    # min x1 + 2 x2 + 3 x3, x1 + x2 + x3 = 2 (=), x1 <= 0.5 (<=), 0 <= x <= 1
    matrix = csr_matrix(np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    res = minimise(
        np.array([1.0, 2.0, 3.0]),
        np.zeros(3),
        np.ones(3),
        np.array([-np.inf, 2.0]),
        np.array([0.5, 2.0]),
        matrix,
    )
    assert res.status == "optimal"
    assert np.allclose(res.x, [0.5, 1.0, 0.5])
    # the = row's dual is the price of one more unit (x3's cost), the binding <= row's is <= 0
    assert np.allclose(res.duals, [-2.0, 3.0])
    # weak duality with 0 <= x <= 1: b·y + sum(min(0, c - Aᵀy)) is the optimum here
    reduced = np.array([1.0, 2.0, 3.0]) - matrix.T @ res.duals
    assert np.isclose(0.5 * res.duals[0] + 2.0 * res.duals[1] + np.minimum(reduced, 0.0).sum(), 4.0)


def test_an_infeasible_lp_says_so() -> None:
    # x1 + x2 = 3 with both at most 1
    res = minimise(
        np.ones(2), np.zeros(2), np.ones(2), np.array([3.0]), np.array([3.0]), csr_matrix(np.array([[1.0, 1.0]]))
    )
    assert res.status == "infeasible"
    assert res.x.size == 0 and res.duals.size == 0
