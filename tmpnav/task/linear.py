"""Linear programs by OR-Tools' simplex solver GLOP (the adapter: with :mod:`tmpnav.task.routing`,
the only modules that import OR-Tools).

Used by the lower bound's relaxation (:mod:`tmpnav.task.bound_lp`). It replaced scipy's
``linprog(method="highs")``, whose import (all of scipy.optimize) took 0.2-0.3 s of every fresh
tmpnav process; on 155 tables of tests/task/instances.py, 2 to 60 rooms, the bounds agree to
1e-15 (relative). The model is handed over as arrays (no model built a term at a time).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix

Floats = NDArray[np.float64]

#: GLOP's dual simplex: on tests/task/instances.py's 60-room, 8-robot table the bound took
#: 7.4 s with it, 33.9 s with GLOP's default primal simplex, 8.3 s with scipy's HiGHS before
GLOP_PARAMETERS = "use_dual_simplex: true"


@dataclass(frozen=True)
class LpSolution:
    """A solved linear program: the solver's status (``optimal``, ``infeasible`` or another of
    OR-Tools' statuses, in lower case), the solution and the rows' duals (each the objective's
    rate of change with its row's bound; in a minimisation, <= 0 on a <= row at its bound).
    Both arrays are empty unless the status is ``optimal``."""

    status: str
    x: Floats
    duals: Floats


def minimise(
    cost: Floats, lower: Floats, upper: Floats, row_lower: Floats, row_upper: Floats, matrix: csr_matrix
) -> LpSolution:
    """min cost·x subject to row_lower <= matrix x <= row_upper and lower <= x <= upper
    (-inf / inf: no bound)."""
    from ortools.linear_solver.python import model_builder_helper as mb

    model = mb.ModelBuilderHelper()
    # OR-Tools' stub types each array as numpy.ndarray[numpy.float64[m, 1]], which no array is
    model.fill_model_from_sparse_data(lower, upper, cost, row_lower, row_upper, matrix)  # type: ignore[arg-type]
    solver = mb.ModelSolverHelper("glop")
    solver.set_solver_specific_parameters(GLOP_PARAMETERS)
    solver.solve(model)
    status = solver.status()
    if status != mb.SolveStatus.OPTIMAL:
        return LpSolution(status.name.lower(), np.zeros(0), np.zeros(0))
    return LpSolution(
        "optimal", np.asarray(solver.variable_values(), dtype=float), np.asarray(solver.dual_values(), dtype=float)
    )
