"""The suite's order: the longest test files first.

``make test`` runs the files on parallel workers (pytest-xdist, ``--dist loadfile``), each file
on one worker, handed out in collection order as workers come free. Files that take minutes
(end-to-end runs of the planner) handed out last leave the other workers idle at the end; handed
out first, the short files fill in around them (longest processing time first). The weights are
rough seconds on a 2-core machine, measured with ``pytest --durations`` beside the rest of the
suite; a file not listed runs after these, in its usual order.
"""

from __future__ import annotations

import pytest

#: test file (relative to the repository) -> rough seconds it takes
HEAVY: dict[str, float] = {
    "tests/test_team_objective.py": 300,  # shifts planned cold with both objectives
    "tests/oracle/test_ray.py": 170,  # a local Ray instance: seconds alone, minutes beside the suite
    "tests/test_cli_risk.py": 150,
    "tests/test_regression.py": 110,
    "tests/test_fault_injection.py": 110,
    "tests/test_cli_bench.py": 85,
    "tests/fuzz/test_fuzz_cli.py": 75,
    "tests/attachment/test_unfold.py": 63,
    "tests/test_cli_files.py": 63,
    "tests/task/test_search.py": 60,
    "tests/test_jobs.py": 55,
    "tests/rooms/test_cli_rooms.py": 47,
    "tests/belief/test_kernel.py": 45,
    "tests/export/test_nav2_building.py": 41,
    "tests/task/test_windows.py": 40,
    "tests/test_replan.py": 40,
    "tests/oracle/test_cache.py": 36,
    "tests/test_cli_plan.py": 35,
    "tests/task/test_objectives.py": 35,
    "tests/task/test_enhsp_persistent.py": 34,
    "tests/task/test_pddl_text.py": 33,
    "tests/test_depot_jobs.py": 30,
    "tests/test_cli_search.py": 26,
    "tests/test_reproducible.py": 60,  # two fresh plans of the corridor, one beside two CPU-bound processes
    "tests/test_time_limit.py": 30,
    "tests/planning/test_remember.py": 25,
    "tests/task/test_bound.py": 25,
    "tests/oracle/test_worker_lifetime.py": 19,
    "tests/rooms/test_segment.py": 18,
    "tests/test_closed_loop.py": 15,
    "tests/test_stations.py": 30,  # one plan of five stations and a dock, its nav2 files, one replan
    "tests/replan/test_seeded.py": 90,  # seeded replans of a 9-station shift
    "tests/replan/test_shift.py": 90,
    "tests/execution/test_rpp.py": 40,  # one simulate of two-rooms
    "tests/serve/test_bad_input.py": 80,  # tests/serve: a real `tmpnav serve` per file, planning two-rooms
    "tests/serve/test_service.py": 60,
    "tests/serve/test_restart.py": 50,
    "tests/serve/test_view.py": 45,
    "tests/serve/test_closed_loop.py": 40,  # a real `tmpnav serve` and a closed-loop session against it
    "tests/execution/test_moves.py": 25,  # one plan of the replan tests' world
}


def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    """The heaviest files' tests first, each file's tests in their own order."""

    def weight(item: pytest.Item) -> float:
        path = item.nodeid.split("::", 1)[0]
        return -HEAVY.get(path, 0.0)

    items.sort(key=weight)  # a stable sort: the order within each weight stays
