"""One small real plan per test session, shared by the report tests.

Three rooms off a corridor, two robots: r1 must visit C then B, r2 must visit A. Planned for
the paper's objective (the sum of action costs, ``--objective cost``) over the cost table
(``--costs table``), the optimal plan moves r1 alone to C, then pairs r1's move to B with r2's
move to A: on the team's shared clock r2 waits 15 s for r1 before they start together, and r1
is idle after its last move until r2 arrives. Every part of the schedule's report (a solo move,
a paired move, a wait, idle time) gets exercised.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.pipeline import PlanOptions, plan
from tmpnav.results import PlanReport

ROOT = Path(__file__).resolve().parents[2]

THREE_ROOMS = """\
name: three-rooms
description: "Three rooms off a short corridor, for the report tests"
map:
  bounds: [0, 0, 12, 8]
  resolution: 0.05
  walls:
    - [[0, 0], [12, 0], [12, 8], [0, 8], [0, 0]]
    - [[0, 4], [2.4, 4]]
    - [[3.6, 4], [8.4, 4]]
    - [[9.6, 4], [12, 4]]
    - [[6, 4], [6, 8]]
rooms:
  - {name: A, polygon: [[0.2, 4.2], [5.8, 4.2], [5.8, 7.8], [0.2, 7.8]]}
  - {name: B, polygon: [[6.2, 4.2], [11.8, 4.2], [11.8, 7.8], [6.2, 7.8]]}
  - {name: C, polygon: [[0.2, 0.2], [11.8, 0.2], [11.8, 3.8], [0.2, 3.8]]}
doors:
  - {name: door-A, segment: [[2.4, 4], [3.6, 4]], state: open}
  - {name: door-B, segment: [[8.4, 4], [9.6, 4]], state: open}
landmarks:
  - {name: printer, kind: printer, position: [1.0, 7.5]}
  - {name: plant, kind: plant, position: [11.0, 0.5]}
robots:
  - {name: r1, pose: [3.0, 6.0, -1.5708]}
  - {name: r2, pose: [9.0, 6.0, -1.5708]}
roadmap: {samples: 200, instantiations: 2, seed: 3}
goals:
  robots:
    r1: [C, B]
    r2: [A]
"""


@pytest.fixture(scope="session")
def plan_report(tmp_path_factory: pytest.TempPathFactory) -> PlanReport:
    """The real plan of the three-rooms scenario (about 3 s: roadmap, oracle, ENHSP, re-simulation),
    as planned: its paired move and the robot waiting for its partner, its conflict reported
    (kept apart, a plan of single moves: :func:`kept_report`)."""
    folder = tmp_path_factory.mktemp("three-rooms")
    scenario = folder / "three_rooms.yaml"
    scenario.write_text(THREE_ROOMS)
    options = PlanOptions.of(
        cache_dir=folder / "cache", executor="serial", costs="table", objective="cost", keep_apart=False
    )
    return plan(scenario, options)


@pytest.fixture(scope="session")
def kept_report(tmp_path_factory: pytest.TempPathFactory) -> PlanReport:
    """The same plan with the default keep_apart: its paired move split in two and one robot
    held back, so that they no longer meet."""
    folder = tmp_path_factory.mktemp("three-rooms-kept")
    scenario = folder / "three_rooms.yaml"
    scenario.write_text(THREE_ROOMS)
    options = PlanOptions.of(cache_dir=folder / "cache", executor="serial", costs="table", objective="cost")
    return plan(scenario, options)


@pytest.fixture(scope="session")
def plan_doc(plan_report: PlanReport) -> dict:
    from tmpnav.report.plan_json import plan_document

    return plan_document(plan_report)
