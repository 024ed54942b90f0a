"""The same scenario and options give the same plan.json, timings aside, on a busy machine.

The anytime search's budget is work (tmpnav.task.budget): the corridor of `make demo` planned
with two CPU-bound processes beside it gives the plan it gives without them. It compares
plans, never durations: however slow the loaded run, it must not change the plan.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tmpnav.report.plan_json import without_timings

ROOT = Path(__file__).resolve().parents[1]
CORRIDOR = ROOT / "configs" / "corridor.yaml"


@contextmanager
def busy(processes: int = 2) -> Iterator[None]:
    """``processes`` CPU-bound processes beside the block (one per core of the 2-core machine)."""
    hogs = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(processes)]
    try:
        yield
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def plan_json(scenario: Path) -> dict[str, Any]:
    """plan.json of a fresh ``tmpnav plan``, every cost computed (no cache), default options."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", str(scenario), "--no-cache", "--format", "json", "-q"],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


@pytest.mark.slow
def test_the_corridor_plans_the_same_beside_two_cpu_bound_processes() -> None:
    idle = plan_json(CORRIDOR)
    with busy():
        loaded = plan_json(CORRIDOR)
    assert idle["search"]["capped"] == [] and loaded["search"]["capped"] == []
    assert without_timings(loaded) == without_timings(idle)
    # the converged plan of `make demo`: the paired move, not two single moves kept apart
    assert idle["search"]["stopped"] == "converged"
    assert [a["robots"] for a in idle["actions"]] == [["r1", "r2"]]
