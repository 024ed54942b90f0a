"""The oracle's disk cache: content-addressed keys, integrity, crash safety."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tests.oracle.support import actions, variant
from tmpnav.cachedir import DATABASE as FILENAME
from tmpnav.cachedir import CacheDir
from tmpnav.oracle.cache import CacheWarning, DiskCache, NullCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.keys import context_digest, request_key
from tmpnav.oracle.oracle import Oracle
from tmpnav.roadmap import build_roadmap
from tmpnav.types import Door, RoadmapParams
from tmpnav.world import build

ROOT = Path(__file__).resolve().parents[2]


def keys(ctx: OracleContext) -> list[str]:
    context = context_digest(ctx.scenario, ctx.world, ctx.roadmap)
    return [request_key(context, ctx.scenario, r) for r in actions(ctx)]


def test_unchanged_scenario_same_keys(two_rooms: OracleContext) -> None:
    assert keys(two_rooms) == keys(two_rooms)
    assert len(set(keys(two_rooms))) == len(actions(two_rooms))


def test_every_input_changes_the_keys(two_rooms: OracleContext) -> None:
    sc = two_rooms.scenario
    base = set(keys(two_rooms))
    noise = variant(two_rooms, models=replace(sc.models, motion_noise=(0.02, *sc.models.motion_noise[1:])))
    weight = variant(two_rooms, cost=replace(sc.cost, M_Sigma=2.0))
    seed = variant(two_rooms, models=replace(sc.models, seed=sc.models.seed + 1))
    sensor = variant(two_rooms, models=replace(sc.models, mutual_sensor=replace(sc.models.mutual_sensor, range=3.0)))
    speed = variant(two_rooms, robots=tuple(replace(r, speed=0.4) for r in sc.robots))
    # a different map: door B half closed changes the world's fingerprint
    doors = (sc.doors[0], Door("door-B", ((8.4, 4.0), (9.0, 4.0)), False, 0.15))
    walled_sc = replace(sc, doors=doors)
    walled_world = build(walled_sc)
    walled = OracleContext(walled_sc, walled_world, two_rooms.roadmap)
    reseeded = replace(two_rooms, roadmap=build_roadmap(two_rooms.world, sc.robots, RoadmapParams(300, 3, 2, 10)))
    for name, ctx in [
        ("noise", noise),
        ("weight", weight),
        ("observation seed", seed),
        ("sensor", sensor),
        ("speed", speed),
        ("map", walled),
        ("roadmap seed", reseeded),
    ]:
        assert base.isdisjoint(keys(ctx)), name


def test_every_field_of_a_request_changes_its_key(two_rooms: OracleContext) -> None:
    """Each field of a request, and each number of its start states, enters its key (the keys
    hash floats by their bits: a field the key forgot would share results between requests)."""
    from dataclasses import fields

    from tmpnav.oracle.requests import Request, StartState

    sc = two_rooms.scenario
    context = context_digest(sc, two_rooms.world, two_rooms.roadmap)
    pair = next(r for r in actions(two_rooms) if r.n == 2)
    joint = tuple(tuple(float(v) for v in row) for row in pair.cov0())
    base = replace(pair, joint_cov=joint)
    key = request_key(context, sc, base)
    start = base.starts[0]
    changed = {
        "robots": replace(base, robots=base.robots[::-1]),
        "starts": replace(base, starts=base.starts[::-1]),
        "rooms": replace(base, rooms=(base.rooms[0], next(r.name for r in sc.rooms if r.name != base.rooms[1]))),
        "joint_cov": replace(base, joint_cov=None),
        "min_gain": replace(base, min_gain=0.05),
        "bound_only": replace(base, bound_only=True),
        "max_risk": replace(base, max_risk=0.1),
    }
    assert set(changed) == {f.name for f in fields(Request)}
    nudged = float(np.nextafter(1.0, 2.0))
    for name in (f.name for f in fields(StartState)):
        value = getattr(start, name)
        if name == "node":
            value = value + 1
        elif name == "heading":
            value = value * nudged if value else 1e-300
        elif name == "mean":
            value = (value[0], value[1] * nudged, value[2])
        else:
            value = (value[0], value[1], (value[2][0], value[2][1], value[2][2] * nudged))
        changed[f"starts.{name}"] = replace(base, starts=(replace(start, **{name: value}), *base.starts[1:]))
    changed["joint_cov entry"] = replace(base, joint_cov=(*joint[:-1], (*joint[-1][:-1], joint[-1][-1] * nudged)))
    for name, request in changed.items():
        assert request_key(context, sc, request) != key, name
    assert request_key(context, sc, replace(base)) == key


def test_truncated_cache_is_detected_and_recomputed(two_rooms: OracleContext, tmp_path: Path) -> None:
    reqs = actions(two_rooms)
    reference = Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(reqs)
    path = tmp_path / FILENAME
    for suffix in ("-wal", "-shm"):
        Path(str(path) + suffix).unlink(missing_ok=True)
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.warns(CacheWarning) as caught:
        oracle = Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor())
        again = oracle.evaluate(reqs)
    assert again == reference
    assert len(caught) == 1, [str(w.message) for w in caught]
    assert oracle.stats.cache_misses == len(set(keys(two_rooms)))


def test_garbage_cache_is_detected_and_recomputed(two_rooms: OracleContext, tmp_path: Path) -> None:
    reqs = actions(two_rooms)[:5]
    reference = Oracle(two_rooms, NullCache(), SerialExecutor()).evaluate(reqs)
    (tmp_path / FILENAME).write_bytes(np.random.default_rng(0).bytes(20000))
    with pytest.warns(CacheWarning, match="unreadable|corrupted"):
        assert Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(reqs) == reference
    # and the fresh cache works afterwards, silently
    assert Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(reqs) == reference


def test_tampered_entry_fails_its_checksum(two_rooms: OracleContext, tmp_path: Path) -> None:
    reqs = actions(two_rooms)[:3]
    reference = Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(reqs)
    conn = sqlite3.connect(tmp_path / FILENAME)
    conn.execute("UPDATE entries SET value = replace(value, '\"cost\":', '\"cost\":9')")
    conn.commit()
    conn.close()
    with pytest.warns(CacheWarning, match="integrity"):
        assert Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(reqs) == reference


def test_info_and_clear(two_rooms: OracleContext, tmp_path: Path) -> None:
    Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor()).evaluate(actions(two_rooms)[:4])
    facts = CacheDir(tmp_path).info()
    assert facts.entries == 4
    assert CacheDir(tmp_path).clear()[0] >= 1
    assert CacheDir(tmp_path).info().database_exists is False


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_killed_precompute_leaves_a_usable_cache(tmp_path: Path, sig: signal.Signals) -> None:
    """Kill ``tmpnav plan`` while the oracle writes; the next run must succeed."""
    scenario = tmp_path / "ten.yaml"
    text = (ROOT / "configs" / "corridor.yaml").read_text()
    text = text.replace(
        "goals:\n  robots:\n    r1: [L10]\n    r2: [L1]", "goals:\n  visit: [L2, L3, L4, L5, L6, L7, L8, L9]"
    )
    scenario.write_text(text)
    cache = tmp_path / "cache"
    cmd = [sys.executable, "-m", "tmpnav", "plan", str(scenario), "--cache-dir", str(cache), "-q", "--workers", "2"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and not (cache / FILENAME).exists():
        time.sleep(0.05)
    time.sleep(1.0)  # the oracle is writing its first waves of results
    os.killpg(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    if sig == signal.SIGINT and proc.returncode != 0:
        assert proc.returncode == 130, err
        assert "Traceback" not in err
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "warning" not in done.stderr
