"""Every way of computing an action gives bit-identical results.

Through the cache and without it, in this process, in 1 and 2 local workers (and on a real local
Ray instance: tests/oracle/test_ray.py): the same costs, goal instantiations, paths and final beliefs.
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path

import pytest

from tests.oracle.support import actions
from tmpnav.oracle import executors
from tmpnav.oracle.cache import DiskCache, NullCache
from tmpnav.oracle.executors import OracleContext, ProcessExecutor, SerialExecutor
from tmpnav.oracle.oracle import Oracle


@pytest.fixture(scope="module")
def reference(two_rooms: OracleContext):  # type: ignore[no-untyped-def]
    return Oracle(two_rooms, NullCache(), SerialExecutor()).evaluate(actions(two_rooms))


def test_reference_is_complete(reference) -> None:  # type: ignore[no-untyped-def]
    assert all(r is not None for r in reference)
    pairs = [r for r in reference if len(r.robots) == 2]
    assert any(r.mutual_steps > 0 for r in pairs), "some pair should observe each other"


def test_cache_returns_what_was_computed(two_rooms: OracleContext, reference, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    first = Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor())
    assert first.evaluate(actions(two_rooms)) == reference
    assert first.stats.cache_misses > 0 and first.stats.cache_hits == 0
    second = Oracle(two_rooms, DiskCache(tmp_path), SerialExecutor())
    assert second.evaluate(actions(two_rooms)) == reference
    assert second.stats.cache_misses == 0 and second.stats.cache_hits == first.stats.cache_misses


@pytest.mark.parametrize("workers", [1, 2])
def test_local_workers(two_rooms: OracleContext, reference, workers: int, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(executors, "BLOCK", 4)  # several blocks, so two workers share the work
    result = Oracle(two_rooms, NullCache(), ProcessExecutor(workers)).evaluate(actions(two_rooms))
    assert result == reference


def test_workers_forked_while_the_parent_holds_its_signals_take_sigterm(
    two_rooms: OracleContext, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The first blocks fork the workers under tmpnav.lifetime.signals_held, and a fork keeps the
    signal mask: a worker that kept SIGTERM blocked ignored the terminate of a stopped wave (Ctrl-C,
    a time limit), and the parent waited 5 s for each before it killed it."""
    monkeypatch.setattr(executors, "BLOCK", 4)
    executor = ProcessExecutor(2)
    try:
        Oracle(two_rooms, NullCache(), executor).evaluate(actions(two_rooms))
        pool = executor._pool
        assert pool is not None
        masks = [pool.submit(signal.pthread_sigmask, signal.SIG_BLOCK, []).result() for _ in range(4)]
    finally:
        executor.close()
    assert all(signal.SIGTERM not in mask for mask in masks)


def test_blocks_keep_start_groups_together(two_rooms: OracleContext) -> None:
    reqs = actions(two_rooms)
    blocks, order = executors.blocks(reqs, size=4)
    assert sorted(order) == list(range(len(reqs)))
    seen: dict[tuple, int] = {}
    for k, block in enumerate(blocks):
        for r in block:
            key = (r.robots, r.starts)
            assert seen.setdefault(key, k) == k


def test_workers_hand_their_cells_to_the_parent(monkeypatch: pytest.MonkeyPatch) -> None:
    """Local workers send back the reach and scan cells they computed (World.take_new); the
    parent's world then holds them, counted as computed in this run, and evaluating the same
    requests in the parent computes none again and gives the workers' results."""
    from dataclasses import replace

    from tests.oracle.support import make_two_rooms
    from tests.oracle.test_motions import LIDAR

    base = make_two_rooms()
    ctx = replace(base, scenario=replace(base.scenario, models=replace(base.scenario.models, range_sensor=LIDAR)))
    requests = [replace(r, max_risk=0.05) for r in actions(ctx)]
    monkeypatch.setattr(executors, "BLOCK", 4)
    pool = ProcessExecutor(2)
    try:
        results, _ = pool.run(ctx, requests)
    finally:
        pool.close()
    scans, reach = ctx.world.scans(LIDAR), ctx.world.reach(ctx.scenario.robots[0].radius)
    learned_scans, learned_reach = scans.size, reach.rows
    assert learned_scans > 1 and learned_reach > 1 and scans.computed == learned_scans - 1
    again, _ = SerialExecutor().run(ctx, requests)
    assert again == results
    assert (scans.size, reach.rows) == (learned_scans, learned_reach)  # nothing computed twice


def test_the_terminated_pools_manager_thread_prints_no_traceback() -> None:
    """Only the thread quieted (the pool's manager, its workers terminated) is silenced; the
    others still reach the hook that was there before."""
    import threading

    def fail() -> None:
        raise OSError("a worker's pipe closed")

    saved, reported = threading.excepthook, []
    try:
        threading.excepthook = lambda args: reported.append(args.thread)
        quiet, loud = threading.Thread(target=fail), threading.Thread(target=fail)
        executors._quiet(quiet)
        for thread in (quiet, loud):
            thread.start()
            thread.join()
        assert reported == [loud]
    finally:
        threading.excepthook = saved


def test_an_idle_pool_is_let_go_and_the_next_wave_forks_workers_that_agree(
    two_rooms: OracleContext, reference, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    """Workers no wave used for idle_seconds end (their memory with them); a later wave starts
    new ones and gets the same results. Waves closer together keep one pool, unless the caller
    lets it go."""
    import time

    monkeypatch.setattr(executors, "BLOCK", 4)
    pool = ProcessExecutor(2, idle_seconds=0.2)
    try:
        first, _ = pool.run(two_rooms, actions(two_rooms))
        workers = list(pool._pool._processes.values())  # type: ignore[union-attr]
        if sys.platform.startswith("linux"):  # named where ps and top show them
            assert {Path(f"/proc/{w.pid}/comm").read_text().strip() for w in workers} == {"tmpnav-oracle"}
        deadline = time.monotonic() + 30
        while pool._pool is not None and time.monotonic() < deadline:
            time.sleep(0.05)
        assert pool._pool is None and not any(w.is_alive() for w in workers)
        second, _ = pool.run(two_rooms, actions(two_rooms))
        assert pool.started == 2 and first == second == reference
    finally:
        pool.close()
    kept = ProcessExecutor(2, idle_seconds=60)
    try:
        kept.run(two_rooms, actions(two_rooms))
        kept.run(two_rooms, actions(two_rooms))
        assert kept.started == 1 and kept._pool is not None
        kept.let_go()  # the caller knows no wave is near
        assert kept._pool is None
        again, _ = kept.run(two_rooms, actions(two_rooms))
        assert kept.started == 2 and again == reference
    finally:
        kept.close()
    assert kept._pool is None and kept._idle is None


def test_a_worker_takes_the_cells_the_others_computed_from_the_news(monkeypatch: pytest.MonkeyPatch) -> None:
    """The news of a wave (executors.News: what the parent learned from the blocks finished)
    puts the other workers' cells into a worker's world, so that it computes none of them
    again; entries it took before are not taken twice, and a new wave's log starts afresh."""
    import numpy as np

    from tests.oracle.support import make_two_rooms
    from tests.oracle.test_motions import LIDAR
    from tmpnav.world.build import Learned

    monkeypatch.setattr(executors, "_TAKEN", [-1, 0])  # this process's, as a fresh worker's
    one, other = make_two_rooms().world, make_two_rooms().world
    radius = 0.3
    for world in (one, other):
        world.take_new()  # both record what they compute, as workers do
    poses = np.array([[1.0, 1.0, 0.0], [2.0, 1.5, 1.0], [3.0, 2.0, 2.0]])
    scans = one.scans(LIDAR)
    scans.rows(scans.keys(poses))
    one.reach(radius).rows_of(one.reach(radius).cells(poses))
    computed = one.take_new()
    assert computed and other.learn(computed)  # the parent's log holds what it did not know
    taken = executors._take_news(other, executors.News(wave=7, start=0, entries=(computed,)))
    assert taken == 1
    other.scans(LIDAR).rows(other.scans(LIDAR).keys(poses))
    other.reach(radius).rows_of(other.reach(radius).cells(poses))
    assert not other.take_new()  # nothing computed: every cell came with the news
    assert not other.learn(computed)  # and known, so the parent would log nothing of it again
    empty = Learned({}, {})
    assert executors._take_news(other, executors.News(wave=7, start=0, entries=(computed, empty))) == 2
    assert executors._take_news(other, executors.News(wave=8, start=0, entries=())) == 0


@pytest.mark.parametrize("queued", [1, 2])
def test_workers_with_the_news_give_the_same_results(
    two_rooms: OracleContext, reference, queued: int, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    """Blocks submitted a few at a time, each with the news of those finished before: the same
    results as in this process."""
    monkeypatch.setattr(executors, "BLOCK", 2)
    monkeypatch.setattr(executors, "QUEUED", queued)
    pool = ProcessExecutor(2)
    try:
        assert Oracle(two_rooms, NullCache(), pool).evaluate(actions(two_rooms)) == reference
    finally:
        pool.close()
