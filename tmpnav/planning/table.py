"""The whole cost table of a run: every move and paired move its encoding may need."""

from __future__ import annotations

from collections.abc import Mapping

from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import Origin, build_table, start_locations
from tmpnav.results import StageTimes
from tmpnav.task.encodings import ENCODINGS
from tmpnav.types import CostTable, Scenario
from tmpnav.world import World


def full_table(
    scenario: Scenario, world: World, oracle: Oracle, times: StageTimes, origin: Mapping[str, Origin] | None = None
) -> CostTable:
    """Every cost the encoding may need, before the exact planner runs (stage ``oracle``);
    ``origin``: a replan's (:func:`tmpnav.oracle.table.origins`)."""
    with times.timed("oracle"):
        sp = scenario.planner
        want = ENCODINGS[sp.encoding].table_request(scenario.goals, start_locations(scenario, world), sp.pair_min_gain)
        return build_table(
            oracle,
            world,
            want.destinations,
            want.pair_filter,
            filter_key=want.filter_key,
            pair_min_gain=want.pair_min_gain,
            origin=origin,
        )
