"""Pair pruning (oracle/bounds.py): the bound never exceeds the joint cost it stands for."""

from __future__ import annotations

from dataclasses import replace

from tests.oracle.support import actions
from tmpnav.oracle.bounds import cannot_save
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.oracle import Oracle


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
