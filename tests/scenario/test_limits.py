"""Resource caps (scenario/limits.py) and the estimates they are checked against."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, build_world, write_yaml
from tmpnav.belief.controls import path_controls
from tmpnav.errors import InputError
from tmpnav.scenario.limits import (
    CAPS,
    MAP_CELLS,
    MOVE_STEPS,
    encoding_table,
    grid_cells,
    move_steps,
    table_entries,
)


def test_every_cap_has_its_own_environment_variable() -> None:
    assert len({c.env for c in CAPS}) == len(CAPS)
    assert all(c.env == f"TMPNAV_MAX_{c.name.upper()}" and c.default >= 1 for c in CAPS)


@pytest.mark.parametrize(
    ("text", "value"), [("1000", 1000), ("6e7", 60_000_000), ("64_000_000", 64_000_000), (" ", None)]
)
def test_a_cap_reads_its_environment_variable(text: str, value: int | None, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(MAP_CELLS.env, text)
    assert MAP_CELLS.value() == (value or MAP_CELLS.default)


@pytest.mark.parametrize("text", ["lots", "0", "-3", "2.5", "nan", "inf", "1e400"])
def test_a_bad_cap_is_bad_input(text: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(MAP_CELLS.env, text)
    with pytest.raises(InputError, match=f"environment variable TMPNAV_MAX_MAP_CELLS={text!r}"):
        MAP_CELLS.value()


def test_a_refusal_gives_the_estimate_the_cap_and_how_to_lift_it() -> None:
    assert MOVE_STEPS.refusal(123456.2, "a higher speed") == (
        "123,457 control steps for a move across the map; the cap is 100,000 "
        "(a higher speed, or raise the cap: TMPNAV_MAX_MOVE_STEPS=123457)"
    )
    assert MOVE_STEPS.refusal(1e20, "a higher speed") == (
        "about 1e+20 control steps for a move across the map; the cap is 100,000 (a higher speed)"
    )
    assert MOVE_STEPS.refusal(math.inf, "x").startswith("more than 1e308 control steps")
    assert MOVE_STEPS.refusal(10**400, "x").startswith("more than 1e308 control steps")


def test_grid_cells_never_overflow() -> None:
    assert grid_cells(10, 6, 0.1) == 6000
    assert grid_cells(2.9, 1, 0.1) == 290  # (0.2 - -2.7) / 0.1 = 29.000000000000004 is 29 columns
    assert grid_cells(math.inf, 1, 0.1) == math.inf
    assert grid_cells(2e308 / 2, 1e308, 1e-300) == math.inf


@pytest.mark.parametrize(("speed", "turn_rate", "dt"), [(0.5, 1.0, 0.5), (0.05, 0.2, 0.1), (2.0, 3.0, 0.01)])
def test_the_step_estimate_covers_a_move_across_the_map(speed: float, turn_rate: float, dt: float) -> None:
    """A move along the map's border (width then height, turning twice by a right angle
    plus a half turn to start) takes no more steps than the estimate."""
    width, height = 10.0, 6.0
    path = np.array([[0.0, 0.0], [width, 0.0], [width, height]])
    steps = path_controls(path, math.pi, speed, turn_rate, dt).n_steps
    drive, turn = move_steps(width, height, speed, turn_rate, dt)
    assert steps <= drive + turn <= 1.5 * steps + 10


def test_the_step_estimate_does_not_overflow() -> None:
    assert move_steps(10, 10, 1e-320, 1.0, 1e-10) == (math.inf, math.inf)
    drive, turn = move_steps(10, 10, 1e-300, 1e-300, 1e-10)
    assert drive == turn == math.inf


def test_encoding_tables_come_from_the_task_encodings() -> None:
    assert {name: encoding_table(name) for name in ("paper", "single", "mixed")} == {
        "paper": ("all-rooms", True),
        "single": ("goals", False),
        "mixed": ("goals", True),
    }


@pytest.mark.parametrize("encoding", ["single", "mixed", "paper"])
def test_the_table_estimate_bounds_what_the_oracle_enumerates(encoding: str, tmp_path: Path) -> None:
    """The estimate counts like oracle/table.py: d² single moves per robot, and every pair
    of single moves of two robots before the encoding's filter; it must not fall below
    the exact count (singles from the real start, pairs after the real filter)."""
    from tmpnav.oracle.table import destinations, start_locations
    from tmpnav.task.encodings import ENCODINGS

    doc = base_scenario()
    doc["goals"] = {"visit": ["A", "B", "hall"], "robots": {"r1": ["B"]}}
    doc["planner"] = {"encoding": encoding}
    scenario, world = build_world(tmp_path, doc)
    starts = start_locations(scenario, world)
    dests = destinations(scenario, ENCODINGS[encoding].destinations)
    singles = [
        (r, a, b)
        for r in dests
        for a in (starts[r], *dests[r])
        for b in dests[r]
        if a != b and (a == starts[r] or a in dests[r])
    ]
    exact = len(singles)
    keep = ENCODINGS[encoding].pair_filter(scenario.goals, starts)
    if keep is not None:
        exact += sum(1 for m1 in singles for m2 in singles if m1[0] < m2[0] and keep(m1, m2))
    estimate = table_entries([len(dests[r.name]) for r in scenario.robots], encoding)
    assert exact <= estimate <= 3 * exact + 10  # three rooms: the filter drops a large share


def test_the_table_estimate_is_close_for_many_rooms() -> None:
    """With d goal rooms the mixed filter drops a share that shrinks like 1/d."""
    from tmpnav.task.encodings import ENCODINGS
    from tmpnav.types import Goals

    rooms = [f"R{i}" for i in range(30)]
    starts = {"r1": "r1-start", "r2": "r2-start"}
    singles = {r: [(r, a, b) for a in (starts[r], *rooms) for b in rooms if a != b] for r in starts}
    keep = ENCODINGS["mixed"].pair_filter(Goals(tuple(rooms), ()), starts)
    exact = sum(map(len, singles.values())) + sum(keep(m1, m2) for m1 in singles["r1"] for m2 in singles["r2"])
    estimate = table_entries([30, 30], "mixed")
    assert exact <= estimate <= 1.15 * exact


def test_the_table_estimate_at_the_sizes_that_matter() -> None:
    assert table_entries([60] * 8, "single") == 8 * 3600
    assert table_entries([10, 10], "mixed") == 200 + 100 * 100
    assert table_entries([200, 200], "mixed") == 80_000 + 40_000**2


def test_a_scenario_file_larger_than_the_cap_is_refused_unread(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from tmpnav.errors import ScenarioError
    from tmpnav.scenario import load

    path = write_yaml(tmp_path / "s.yaml", base_scenario())
    monkeypatch.setenv("TMPNAV_MAX_YAML_BYTES", "100")
    with pytest.raises(ScenarioError) as info:
        load(path)
    [problem] = info.value.problems
    assert problem.message.startswith(f"is {path.stat().st_size:,} bytes of YAML; the cap is 100 (")
