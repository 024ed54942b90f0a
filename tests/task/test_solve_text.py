"""ENHSP's engines as tmpnav runs them on its own PDDL text (tmpnav.task.solve.ENHSP_ENGINES):
the same command line, name and optimality as up_enhsp's engine classes, known without
importing unified-planning."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tmpnav.task import enhsp_jvm
from tmpnav.task.solve import ENHSP_ENGINES, engine_class


@pytest.mark.parametrize("planner", sorted(ENHSP_ENGINES))
def test_the_known_engines_are_up_enhsps(planner: str) -> None:
    from unified_planning.engines import OptimalityGuarantee

    cls = engine_class(planner)
    engine = cls()
    known = ENHSP_ENGINES[planner]
    assert known.command("d.pddl", "p.pddl", "plan.txt") == engine._get_cmd("d.pddl", "p.pddl", "plan.txt")
    assert known.name == engine.name
    assert known.optimal == cls.satisfies(OptimalityGuarantee.SOLVED_OPTIMALLY)


def test_the_jar_is_up_enhsps() -> None:
    from up_enhsp.enhsp_planner import ENHSP_JAR

    assert enhsp_jvm.enhsp_jar() == str(ENHSP_JAR)


@pytest.mark.skipif(enhsp_jvm.unavailable() is not None, reason=str(enhsp_jvm.unavailable()))
def test_a_default_plan_does_not_import_unified_planning() -> None:
    """unified-planning's engines module imports ConfigSpace and scipy.stats (0.6-1 s of a
    fresh process); a plan of tmpnav's own PDDL text in the run's JVM needs none of it."""
    code = (
        "import sys\n"
        "from tmpnav import shipped\n"
        "from tmpnav.pipeline import PlanOptions, plan\n"
        "plan(shipped.configs_dir() / 'two-rooms.yaml', PlanOptions.of(use_cache=False, executor='serial'))\n"
        "print(sorted(m for m in ('unified_planning', 'up_enhsp', 'ConfigSpace') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stderr[-2000:]
