"""The rows of a scan table (tmpnav.world.scan_information.ScanInformation.rows): looked up in an
array of every key where the keys are few, searched among the sorted keys known where not, the
same rows and factors either way, learned and pickled alike."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from tests.oracle.support import make_two_rooms
from tmpnav.types import RangeSensor
from tmpnav.world import scan_information
from tmpnav.world.scan_information import ScanInformation

LIDAR = RangeSensor(12.0, 2 * np.pi, 60, 0.05, 0.1, 1.3)


def test_looked_up_rows_are_the_searched_ones(monkeypatch: pytest.MonkeyPatch) -> None:
    world = make_two_rooms().world
    dense = ScanInformation(world.grid, world.signed_distance, LIDAR)
    monkeypatch.setattr(scan_information, "DENSE_KEYS", 0)
    searched = ScanInformation(world.grid, world.signed_distance, LIDAR)
    assert dense._dense is not None and searched._dense is None
    rng = np.random.default_rng(3)
    cells = world.grid.shape[0] * world.grid.shape[1]
    for _ in range(8):
        keys = rng.integers(-1, cells, size=int(rng.integers(1, 300)))
        keys = np.concatenate([keys, keys[: keys.size // 3]])  # some asked for twice
        assert np.array_equal(dense.rows(keys), searched.rows(keys))
    known, factors = dense.contents()
    assert np.array_equal(known, searched.contents()[0]) and np.array_equal(factors, searched.contents()[1])
    copy = pickle.loads(pickle.dumps(dense))
    assert copy._dense is not None and np.array_equal(copy.rows(known), dense.rows(known))
    learner = ScanInformation(world.grid, world.signed_distance, LIDAR)
    assert learner.learn(known[::2], factors[::2])[0].size == known[::2].size
    assert learner.learn(known, factors)[0].size == known.size - known[::2].size
    assert np.array_equal(learner.table[learner.rows(known)], factors) and learner.computed == known.size
