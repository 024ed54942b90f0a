"""The recorded regression plans (benchmarks/regression/) still come out the same.

A change of plan or cost fails here until the baseline is rewritten on purpose with
`make regression-update` (and the new JSON files are committed with the change). The cases the
suite leaves out for their time (``Case.suite``: the paper's encoding on the ten-room corridor)
are checked with every other by `make regression`.
"""

from __future__ import annotations

import json

import pytest

from tmpnav.bench.regression import BASELINE, CASES, compare, run_case


@pytest.mark.slow
@pytest.mark.parametrize("case", [c for c in CASES if c.suite], ids=[c.name for c in CASES if c.suite])
def test_plan_and_cost_unchanged(case) -> None:  # type: ignore[no-untyped-def]
    recorded = json.loads((BASELINE / f"{case.name}.json").read_text())
    assert compare(recorded, run_case(case)) == [], (
        f"run `make regression-update` if the change is intended ({case.why})"
    )


def test_odd_rooms_baselines_show_the_papers_extra_visit() -> None:
    mixed = json.loads((BASELINE / "odd-rooms.json").read_text())
    paper = json.loads((BASELINE / "odd-rooms-paper.json").read_text())
    entered = lambda doc: [m[2] for step in doc["steps"] for m in step]  # noqa: E731
    assert sorted(entered(mixed)) == sorted(mixed["goals"])
    assert len(entered(paper)) == len(paper["goals"]) + 1


def test_a_plan_a_time_cap_cut_short_fails_instead_of_being_compared() -> None:
    recorded = json.loads((BASELINE / "fig2-carried.json").read_text())
    same = {**recorded, "capped": []}
    assert compare(recorded, same) == []
    (diff,) = compare(recorded, {**recorded, "capped": ["the search's time cap"]})
    assert diff.startswith("not compared: the search's time cap cut the search short")
