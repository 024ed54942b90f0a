"""Property-based fuzzing of tmpnav's inputs through the real command line.

Hypothesis generates and mutates whole scenarios, ROS maps (YAML and image) and YAML
texts (strategies.py); each example runs ``python -m tmpnav validate`` (and, for a few
small worlds with model values at the ends of their ranges, ``tmpnav plan``) in a fresh
process with capped memory and time, and checks what a user sees (harness.py): an exit
code from the documented set, one ``error:`` line per problem, no traceback.

In CI this is a smoke run of fixed examples (derandomized, under a minute). ``make fuzz``
runs random examples for about ten minutes (TMPNAV_FUZZ_EXAMPLES) and records its result
in tests/fuzz/RESULTS.md.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, note, settings

from tests.fuzz.harness import (
    PLAN_MEMORY,
    PLAN_SECONDS,
    VALIDATE_MEMORY,
    VALIDATE_SECONDS,
    check_plan,
    check_validate,
    run_tmpnav,
)
from tests.fuzz.strategies import Case, plan_scenarios, ros_scenarios, scenarios

#: examples per property: a smoke run by default; ``make fuzz`` sets a scale factor
SCALE = float(os.environ.get("TMPNAV_FUZZ_EXAMPLES", "0") or 0)
LONG = SCALE > 0


def fuzz_settings(smoke: int, per_scale: int) -> settings:
    return settings(
        max_examples=int(per_scale * SCALE) if LONG else smoke,
        derandomize=not LONG,  # CI sees the same examples every run
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
        print_blob=True,
    )


def write(case: Case, folder: Path) -> None:
    for name, data in case.files.items():
        (folder / name).write_bytes(data)
    for line in case.notes:
        note(line)


def validate(case: Case) -> None:
    with tempfile.TemporaryDirectory(prefix="tmpnav-fuzz-") as tmp:
        folder = Path(tmp)
        write(case, folder)
        check_validate(run_tmpnav(["validate", "scenario.yaml"], folder, VALIDATE_MEMORY, VALIDATE_SECONDS))


def bomb(levels: int, width: int) -> Case:
    """An alias bomb, as strategies.whole_file_attacks draws them: a{i} holds ``width`` aliases of a{i-1}."""
    lines = [f"a0: &a0 [{', '.join(['x'] * width)}]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
    body = "\n".join(lines) + f"\nname: *a{levels - 1}\n"
    return Case({"scenario.yaml": body.encode()}, [f"bomb ({len(body):,} bytes)"])


# The smoke sets are the first examples of a derandomized run (the same ones whatever their
# number). Of the 24 and 18 they once were, those past the first dozen were mostly one mutation
# again (seven of models.mutual_sensor.fov, six of one png-I16 image), 1.3 s each in a fresh
# process; eight of each keep CI within its time (``make fuzz`` runs hundreds), and the two alias
# bombs are given explicitly.
@fuzz_settings(smoke=8, per_scale=200)
@example(bomb(17, 9))
@example(bomb(40, 2))
@given(scenarios())
def test_validate_survives_any_scenario(case: Case) -> None:
    validate(case)


@fuzz_settings(smoke=8, per_scale=150)
@given(ros_scenarios())
def test_validate_survives_any_ros_map(case: Case) -> None:
    validate(case)


@pytest.mark.slow
@fuzz_settings(smoke=2, per_scale=25)
@given(plan_scenarios())
def test_plan_survives_model_values_at_their_limits(case: Case) -> None:
    with tempfile.TemporaryDirectory(prefix="tmpnav-fuzz-") as tmp:
        folder = Path(tmp)
        write(case, folder)
        args = ["plan", "scenario.yaml", "--format", "json", "--no-cache", "--timeout", "60", "--executor", "serial"]
        check_plan(run_tmpnav(args, folder, PLAN_MEMORY, PLAN_SECONDS))
