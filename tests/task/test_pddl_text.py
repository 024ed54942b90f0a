"""The PDDL text tmpnav writes for ENHSP is the unified-planning problem, word for word in meaning.

unified-planning's own parser reads the text back; its validator accepts every plan ENHSP
finds on the text, and ENHSP's optimum on the text equals an exhaustive search over the
same table. Names that collide with the domain's identifiers plan like any other.
"""

from __future__ import annotations

import random
import subprocess
import sys
from pathlib import Path

import pytest

from tests.task.instances import exact_optimum, plan_cost, small_instance, without_pairs
from tmpnav.task.decode import step_cost
from tmpnav.task.encode import encode_task
from tmpnav.task.names import PddlNames
from tmpnav.task.pddl_text import PddlTask, write_task

ROOT = Path(__file__).resolve().parents[2]

#: every identifier of tmpnav's domains and of PDDL that a scenario might use as a name
DOMAIN_WORDS = (
    "robot",
    "location",
    "goto_room",
    "goto_room_pair_1",
    "robot_in",
    "can_move",
    "target",
    "visited",
    "visited_by",
    "act-cost",
    "move-cost",
    "pair-cost",
    "total-cost",
    "object",
    "number",
    "and",
    "not",
    "define",
    "domain",
    "problem",
    "either",
    "when",
    "increase",
    "rob_r1",
    "loc_a",
    "a__b",
    "A",
    "a",
)


def validate_with_unified_planning(task: PddlTask, actions: tuple[tuple[str, tuple[str, ...]], ...]) -> None:
    """Read the text with unified-planning's parser and check the plan with its validator."""
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import PlanValidator

    problem = PDDLReader().parse_problem_string(task.domain, task.problem)
    plan_text = "\n".join(f"({name} {' '.join(params)})" for name, params in actions)
    plan = PDDLReader().parse_plan_string(problem, plan_text)
    with PlanValidator(problem_kind=problem.kind) as validator:
        outcome = validator.validate(problem, plan)
    assert outcome.status == ValidationResultStatus.VALID, outcome


@pytest.mark.slow
# seed 7 stands for seed 1, the next of its kind (3 robots, the mixed encoding, a robot's own target,
# a paired move in the plan): seed 1's 454 paired actions took unified-planning's parser 17 s (21 s
# in CI), seed 7's 95 take 3 s
@pytest.mark.parametrize("seed", [0, 2, 3, 4, 5, 7])
def test_enhsp_on_the_text_finds_the_exhaustive_optimum_and_the_plan_validates(seed: int) -> None:
    table, goals = small_instance(random.Random(seed), 2 + seed % 2, 4, 0.3)
    task = write_task(table, goals, "mixed" if seed % 3 else "single", min_gain=0.0)
    result = task.solve("enhsp-blind", 120)
    validate_with_unified_planning(task, result.actions)
    steps = task.decode(result)
    cost = sum(step_cost(table, s) for s in steps)
    expected = exact_optimum(table if seed % 3 else without_pairs(table), goals)
    assert plan_cost(table, goals, steps) == pytest.approx(cost)
    assert cost == pytest.approx(expected, abs=len(steps) * 1e-3)


def test_the_text_path_is_chosen_for_enhsp_only() -> None:
    table, goals = small_instance(random.Random(1), 2, 3, 0.3)
    assert isinstance(encode_task(table, goals, "mixed", "enhsp-blind"), PddlTask)
    assert isinstance(encode_task(table, goals, "single", "enhsp"), PddlTask)
    assert not isinstance(encode_task(table, goals, "paper", "enhsp-blind"), PddlTask)


def test_names_never_collide() -> None:
    names = PddlNames.of(DOMAIN_WORDS, DOMAIN_WORDS)
    pddl = [*names.robot.values(), *names.location.values()]
    assert len(set(pddl)) == len(pddl) == 2 * len(DOMAIN_WORDS)
    assert not set(pddl) & {w.lower() for w in DOMAIN_WORDS if not w.startswith(("rob_", "loc_"))}
    for word in DOMAIN_WORDS:
        assert names.robot_named(names.robot[word]) == word
        assert names.location_named(names.location[word]) == word


@pytest.mark.slow
def test_rooms_and_robots_named_like_the_domain_plan(tmp_path: Path) -> None:
    """Issue: rooms or robots named like the domain's identifiers validated, then crashed planning."""
    text = (ROOT / "configs" / "two-rooms.yaml").read_text()
    renames = (("{name: A,", "{name: visited,"), ("{name: B,", "{name: act-cost,"), ("{name: C,", "{name: a__b,"))
    for old, new in renames:
        text = text.replace(old, new)
    text = text.replace("r1: [B]", "robot: [act-cost]").replace("r2: [A]", "goto_room: [visited]")
    text = text.replace("{name: r1,", "{name: robot,").replace("{name: r2,", "{name: goto_room,")
    path = tmp_path / "names.yaml"
    path.write_text(text)
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", str(path), "--no-cache", "--workers", "1", "--format", "json"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert '"act-cost"' in proc.stdout and '"goto_room"' in proc.stdout
