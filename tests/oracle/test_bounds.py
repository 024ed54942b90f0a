"""Pair pruning (oracle/bounds.py): the bound never exceeds the joint cost it stands for."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.oracle.support import actions
from tmpnav import shipped
from tmpnav.attachment.canonical import _offered
from tmpnav.oracle import pairs
from tmpnav.oracle.bounds import ControlFloors, cannot_save
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.evaluate import Request
from tmpnav.oracle.executors import OracleContext, SerialExecutor, library
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import initial_state
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap


def test_a_pruned_pair_costs_at_least_its_bound(two_rooms: OracleContext) -> None:
    pairs = [r for r in actions(two_rooms) if r.n == 2]
    full = Oracle(two_rooms, NullCache(), SerialExecutor()).evaluate(pairs)
    # min_gain = 1: a pair would have to cost nothing; every pair the bound rules out is pruned
    oracle = Oracle(two_rooms, NullCache(), SerialExecutor())
    bounded = oracle.evaluate([replace(r, min_gain=1.0) for r in pairs])
    pruned = [(b, f) for b, f in zip(bounded, full, strict=True) if b is not None and b.pruned]
    assert pruned and oracle.stats.sims.pairs_pruned == len(pruned)
    for bound, result in pruned:
        assert result is not None and not result.pruned
        assert bound.cost <= result.cost + 1e-12
        assert bound.paths == () and bound.robots == result.robots
    kept = [(b, f) for b, f in zip(bounded, full, strict=True) if b is not None and not b.pruned]
    assert all(b == f for b, f in kept)  # a pair that is not pruned gets its exact result


def test_the_pruning_margin() -> None:
    assert cannot_save(bound=10.0, alone=10.0, min_gain=0.05)
    assert not cannot_save(bound=9.4, alone=10.0, min_gain=0.05)
    assert not cannot_save(bound=9.501, alone=10.0, min_gain=0.05)  # within the 0.002 rounding margin


def _corridor_pairs() -> tuple[OracleContext, list[Request]]:
    """The shipped corridor's robots moving together from their starts to every two rooms:
    many combinations in which they see each other."""
    scenario, world = load_world(shipped.configs_dir() / "corridor-2robots.yaml")
    ctx = OracleContext(scenario, world, build_roadmap(world, scenario.robots, scenario.roadmap))
    s1, s2 = (initial_state(scenario, ctx.roadmap.starts[r], r) for r in ("r1", "r2"))
    rooms = [room.name for room in scenario.rooms]
    return ctx, [Request(("r1", "r2"), (s1, s2), (a, b)) for a in rooms for b in rooms if a != b]


@pytest.mark.parametrize("min_gain", [0.0, 0.05, 0.3])
def test_combinations_past_their_cutoff_are_skipped_without_changing_what_is_offered(
    min_gain: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A request's result with its dear combinations skipped (bounds.skippable) is exact
    wherever the pair saves ``min_gain``, and pruned with a valid bound elsewhere."""
    ctx, requests = _corridor_pairs()
    full = Oracle(ctx, NullCache(), SerialExecutor()).evaluate(requests)
    bounded_requests = [replace(r, min_gain=min_gain) for r in requests]
    oracle = Oracle(ctx, NullCache(), SerialExecutor())
    bounded = oracle.evaluate(bounded_requests)
    monkeypatch.setattr(pairs, "skippable", lambda bounds, seen, limit: np.zeros(bounds.shape, dtype=bool))
    unskipped = Oracle(ctx, NullCache(), SerialExecutor())
    without = unskipped.evaluate(bounded_requests)
    skipped = unskipped.stats.sims.joint_sims - oracle.stats.sims.joint_sims
    assert skipped > 0 if min_gain < 0.3 else skipped >= 0  # at 0.3 the pruning of requests leaves none
    singles = Oracle(ctx, NullCache(), SerialExecutor())
    for req, b, f, w in zip(requests, bounded, full, without, strict=True):
        assert f is not None and b is not None and w is not None
        moves = zip(req.robots, req.starts, req.rooms, strict=True)
        alone = sum(res.cost for res in singles.evaluate([Request((r,), (s,), (x,)) for r, s, x in moves]) if res)
        if not cannot_save(f.cost, alone, min_gain):  # offered: exact, the same as without skipping
            assert not b.pruned and b == f == w
        elif b.pruned:
            assert b.cost <= f.cost + 1e-12
        else:
            assert b == f


@pytest.mark.parametrize("min_gain", [0.0, 0.05, 0.3])
@pytest.mark.parametrize("sigma_scale", [1.0, 0.01])
def test_a_pair_costs_at_least_its_robots_least_control_efforts(min_gain: float, sigma_scale: float) -> None:
    """ControlFloors: every pair's exact cost is at least the sum of its robots' least M_u c_u
    to their rooms, so a pair it turns away would never be offered. With M_Sigma a hundredth of
    the paper's, uncertainty weighs as little as with a lidar: pairs are turned away."""
    ctx, requests = _corridor_pairs()
    cost = ctx.scenario.cost
    ctx = replace(ctx, scenario=replace(ctx.scenario, cost=replace(cost, M_Sigma=cost.M_Sigma * sigma_scale)))
    oracle = Oracle(ctx, NullCache(), SerialExecutor())
    joint = oracle.evaluate(requests)
    alone = {
        (r, room): res.cost
        for req in requests[:1]
        for r, s in zip(req.robots, req.starts, strict=True)
        for room, res in zip(
            [room.name for room in ctx.scenario.rooms],
            oracle.evaluate([Request((r,), (s,), (room.name,)) for room in ctx.scenario.rooms]),
            strict=True,
        )
        if res is not None
    }
    floors = ControlFloors(library(ctx))
    turned_away = 0
    for req, res in zip(requests, joint, strict=True):
        assert res is not None and not res.pruned
        least = sum(
            floors.least(r, s.node, s.heading, room)
            for r, s, room in zip(req.robots, req.starts, req.rooms, strict=True)
        )
        assert 0.0 < least <= res.cost + 1e-12
        singles = alone[(req.robots[0], req.rooms[0])] + alone[(req.robots[1], req.rooms[1])]
        if floors.cannot_pair(req, singles, min_gain):
            turned_away += 1
            assert not _offered(res.cost, singles, min_gain)
    assert turned_away > 0 or sigma_scale == 1.0 or min_gain == 0.0  # (singles cost at least their least efforts)
