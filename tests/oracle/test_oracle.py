"""The oracle's own checks: a cost that is not a finite number never leaves it."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from tests.oracle.support import actions
from tmpnav.errors import InputError
from tmpnav.oracle.cache import DiskCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.keys import request_key
from tmpnav.oracle.oracle import Oracle

ROOT = Path(__file__).resolve().parents[2]
HUGE = ((1.0e300, 0.0, 0.0), (0.0, 1.0e300, 0.0), (0.0, 0.0, 1.0))


def test_a_non_finite_cost_is_refused_naming_the_move(two_rooms: OracleContext, tmp_path: Path) -> None:
    sc = two_rooms.scenario
    robots = tuple(replace(r, covariance=HUGE) if r.name == "r1" else r for r in sc.robots)
    extreme = replace(two_rooms, scenario=replace(sc, robots=robots))
    oracle = Oracle(extreme, DiskCache(tmp_path), SerialExecutor())
    moves = [a for a in actions(extreme) if a.robots == ("r1",) and a.rooms == ("B",)]
    with pytest.raises(InputError, match=r"cost of r1 moving from roadmap node \d+ \(room A\) to room B is nan"):
        oracle.evaluate(moves)
    keys = [request_key(oracle.context, extreme.scenario, m) for m in moves]
    assert DiskCache(tmp_path).get_many(keys) == {}  # nothing of it was cached


@pytest.mark.slow
def test_the_cli_refuses_such_a_belief_before_any_work(tmp_path: Path) -> None:
    """Through the CLI the same belief never reaches the oracle: validation refuses it first,
    in one line naming the key (the oracle's own check above is the second line of defence)."""
    scenario = (ROOT / "tests" / "fixtures" / "two_rooms.yaml").read_text()
    r1 = "  - {name: r1, pose: [3.0, 6.0, -1.5708]}"
    assert r1 in scenario
    huge = "  - {name: r1, pose: [3.0, 6.0, -1.5708], covariance: [[1.0e+300, 0, 0], [0, 1.0e+300, 0], [0, 0, 1]]}"
    path = tmp_path / "huge.yaml"
    path.write_text(scenario.replace(r1, huge))
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", str(path), "--no-cache", "--workers", "1", "-q"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {path}:"), proc.stderr
    assert "robots.r1.covariance" in lines[0] and "wider than the map" in lines[0]
