"""Stored roadmaps: read back exactly, and any damaged file set aside instead of breaking runs."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from tmpnav.cachedir import CacheDir
from tmpnav.roadmap.store import DAMAGE, RoadmapCacheWarning, RoadmapStore, read, serialize
from tmpnav.types import Roadmap

KEY = "ab" * 32


def small_roadmap() -> Roadmap:
    nodes = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.5], [0.0, 2.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3]], dtype=np.int64)
    weights = np.linalg.norm(nodes[edges[:, 0]] - nodes[edges[:, 1]], axis=1)
    return Roadmap(nodes, edges, weights, {"A": (2, 3)}, {"r1": 0}, "f" * 64)


def same(a: Roadmap, b: Roadmap) -> bool:
    return (
        np.array_equal(a.nodes, b.nodes)
        and np.array_equal(a.edges, b.edges)
        and np.array_equal(a.weights, b.weights)
        and (a.instantiations, a.starts, a.fingerprint) == (b.instantiations, b.starts, b.fingerprint)
    )


def test_a_stored_roadmap_reads_back_exactly(tmp_path: Path) -> None:
    store = RoadmapStore(CacheDir(tmp_path))
    store.save(KEY, small_roadmap())
    found = store.load(KEY)
    assert found is not None and same(found, small_roadmap())
    assert store.load("cd" * 32) is None and store.warnings == []


def damage_truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


def damage_empty(path: Path) -> None:
    path.write_bytes(b"")


def damage_header(path: Path) -> None:
    """A valid archive whose header was edited: an instantiation that is not a node."""
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    header = json.loads(bytes(arrays["header"]).decode())
    header["instantiations"]["A"] = [2, 99]
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def damage_arrays(path: Path) -> None:
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["nodes"] = arrays["nodes"] + 0.5
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


@pytest.mark.parametrize("damage", [damage_truncate, damage_empty, damage_header, damage_arrays])
def test_a_damaged_file_is_set_aside_with_one_warning(tmp_path: Path, damage) -> None:  # type: ignore[no-untyped-def]
    cache = CacheDir(tmp_path)
    RoadmapStore(cache).save(KEY, small_roadmap())
    damage(cache.roadmap(KEY))
    store = RoadmapStore(cache)
    with pytest.warns(RoadmapCacheWarning, match="unreadable") as caught:
        assert store.load(KEY) is None
    assert len(caught) == 1 and len(store.warnings) == 1
    assert not cache.roadmap(KEY).exists()
    assert [p.name.split(".corrupt-")[0] for p in cache.roadmaps.iterdir()] == [f"{KEY}.npz"]  # set aside
    store.save(KEY, small_roadmap())  # and grown again
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = RoadmapStore(cache).load(KEY)
    assert again is not None and same(again, small_roadmap())
    assert cache.info().set_aside == 1 and cache.info().roadmaps == 1


def test_read_rejects_what_serialize_did_not_write(tmp_path: Path) -> None:
    path = tmp_path / "x.npz"
    path.write_bytes(serialize(small_roadmap()))
    assert same(read(path), small_roadmap())
    path.write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(DAMAGE):
        read(path)


def test_a_scan_table_is_kept_beside_the_roadmaps_and_read_back(tmp_path: Path) -> None:
    """What one run computed of a range sensor's scan information, the next preloads: the same
    factors, computed no more; a damaged table is set aside with one warning."""
    import math

    from tests.world.test_lidar import box, world_of
    from tmpnav.roadmap.store import ScanStore
    from tmpnav.types import RangeSensor

    sensor = RangeSensor(8.0, 2 * math.pi, 30, 0.03, 0.1, math.radians(75))
    cache = CacheDir(tmp_path)
    first = world_of(box())
    poses = np.array([[2.0, 1.5, 0.0], [7.5, 4.2, 1.0], [3.3, 3.3, -2.0]])
    scans = first.scans(sensor)
    rows = scans.rows(scans.keys(poses))
    ScanStore(cache, RoadmapStore(cache)).save(first, sensor)
    assert cache.info().roadmaps == 0 and cache.info().roadmap_bytes > 0  # a scan table, not a roadmap
    second = world_of(box())
    assert ScanStore(cache, RoadmapStore(cache)).load(second, sensor) == 3
    again = second.scans(sensor)
    np.testing.assert_array_equal(again.table[again.rows(again.keys(poses))], scans.table[rows])
    assert again.computed == 0
    with open(cache.scans(next(iter(cache.roadmaps.iterdir())).name.split(".")[0]), "r+b") as fh:
        fh.truncate(100)
    store = RoadmapStore(cache)
    with pytest.warns(RoadmapCacheWarning, match="scan table .* is unreadable"):
        assert ScanStore(cache, store).load(world_of(box()), sensor) == 0
    assert cache.info().set_aside == 1


def test_a_localisability_map_is_computed_once_per_map_and_view(tmp_path: Path) -> None:
    """plan.png's localisability map: the second figure of a map reads what the first computed
    (the same numbers), a damaged file is computed again, and no cache means computed."""
    import math

    from tests.world.test_lidar import box, world_of
    from tmpnav.roadmap.store import stored_localisability
    from tmpnav.types import RangeSensor
    from tmpnav.world.scan_information import localisability

    sensor = RangeSensor(8.0, 2 * math.pi, 30, 0.03, 0.1, math.radians(75))
    world, cache, view = world_of(box()), CacheDir(tmp_path), (0.5, 0.5, 6.0, 4.0)
    expected = localisability(world.grid, world.signed_distance, sensor, view, 200)
    first = stored_localisability(cache, world, sensor, view, 200)
    (path,) = list(cache.roadmaps.iterdir())
    assert path.name.endswith(".localisability.npz") and cache.info().roadmaps == 0
    again = stored_localisability(cache, world_of(box()), sensor, view, 200)
    for found in (first, again, stored_localisability(None, world, sensor, view, 200)):
        np.testing.assert_array_equal(found.xs, expected.xs)
        np.testing.assert_array_equal(found.sigma, expected.sigma)
    with open(path, "r+b") as fh:
        fh.truncate(100)
    np.testing.assert_array_equal(stored_localisability(cache, world, sensor, view, 200).sigma, expected.sigma)
    assert cache.info().set_aside == 1
    other = stored_localisability(cache, world, sensor, (0.5, 0.5, 5.0, 4.0), 200)
    assert other.xs.size != expected.xs.size or other.xs[-1] != expected.xs[-1]


def test_a_grown_roadmaps_safe_weights_are_kept_beside_it_and_read_back(tmp_path: Path) -> None:
    """A second process (here: the process's own memo emptied) reads the safe weights the first
    stored, the same bits; a replan's sources add their own edges on top; a damaged file is set
    aside with one warning and the weights computed again."""
    from tests.world.test_lidar import box, world_of
    from tmpnav.roadmap import graph
    from tmpnav.roadmap.store import SafeWeightStore

    world, cache = world_of(box()), CacheDir(tmp_path)
    nodes = np.array([[0.5, 0.5], [4.0, 0.5], [4.0, 2.2], [9.0, 5.0], [2.0, 4.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]], dtype=np.int64)
    lengths = np.linalg.norm(nodes[edges[:, 0]] - nodes[edges[:, 1]], axis=1)
    roadmap = Roadmap(nodes, edges, lengths, {"A": (3,)}, {"r1": 0}, "g" * 64)
    expected = graph.safe_weights(roadmap, world, 0.3, 0.4)
    assert np.any(expected > lengths)  # edges near the walls and the pillar weigh more
    graph._GROWN_WEIGHTS.clear()
    SafeWeightStore(cache, RoadmapStore(cache)).ensure(roadmap, world, 0.3, 0.4)
    (path,) = list(cache.roadmaps.iterdir())
    assert path.name.endswith(".safe.npz") and cache.info().roadmaps == 0
    graph._GROWN_WEIGHTS.clear()
    SafeWeightStore(cache, RoadmapStore(cache)).ensure(roadmap, world, 0.3, 0.4)
    key = (roadmap.grown, world.fingerprint, 0.3, 0.4)
    np.testing.assert_array_equal(graph._GROWN_WEIGHTS[key], expected)
    replan = Roadmap(
        np.vstack([nodes, [[6.0, 4.0]]]),
        np.vstack([edges, [[5, 3]]]),
        np.r_[lengths, np.hypot(3.0, 1.0)],
        {"A": (3,)},
        {"r1": 5},
        "h" * 64,
        sources=(5,),
        base="g" * 64,
    )
    np.testing.assert_array_equal(graph.safe_weights(replan, world, 0.3, 0.4)[:4], expected)
    with open(path, "r+b") as fh:
        fh.truncate(100)
    graph._GROWN_WEIGHTS.clear()
    with pytest.warns(RoadmapCacheWarning, match="safe weights .* are unreadable"):
        SafeWeightStore(cache, RoadmapStore(cache)).ensure(roadmap, world, 0.3, 0.4)
    np.testing.assert_array_equal(graph._GROWN_WEIGHTS[key], expected)
    assert cache.info().set_aside == 1
