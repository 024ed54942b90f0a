"""tmpnav.heap: the objects of a run's start frozen for the run, and only for it."""

from __future__ import annotations

import gc
import weakref

import pytest

from tmpnav.heap import long_lived_frozen


class _Node:
    def __init__(self) -> None:
        self.other: _Node | None = None


def _cycle() -> weakref.ref[_Node]:
    a, b = _Node(), _Node()
    a.other, b.other = b, a
    return weakref.ref(a)


def test_frozen_inside_and_given_back_after() -> None:
    assert gc.get_freeze_count() == 0
    with long_lived_frozen():
        assert gc.get_freeze_count() > 0
    assert gc.get_freeze_count() == 0


def test_garbage_made_inside_is_collected_inside() -> None:
    with long_lived_frozen():
        ref = _cycle()
        gc.collect()
        assert ref() is None


def test_garbage_from_before_is_collected_after() -> None:
    ref = _cycle()
    with long_lived_frozen():
        gc.collect()
        assert ref() is not None  # frozen: not walked
    gc.collect()
    assert ref() is None


def test_nested_runs_give_back_at_the_last_end() -> None:
    with long_lived_frozen():
        with long_lived_frozen():
            pass
        assert gc.get_freeze_count() > 0
    assert gc.get_freeze_count() == 0


def test_given_back_when_the_run_fails() -> None:
    with pytest.raises(RuntimeError), long_lived_frozen():
        raise RuntimeError("the run failed")
    assert gc.get_freeze_count() == 0


def test_what_survives_a_full_collection_inside_is_not_walked_again_until_the_end() -> None:
    with long_lived_frozen():
        keep = _Node()
        keep.other = keep  # a cycle, alive
        gc.collect()  # survives: frozen
        ref = weakref.ref(keep)
        del keep
        gc.collect()
        assert ref() is not None  # unreachable now, but frozen: not walked
    gc.collect()
    assert ref() is None


def test_collections_are_left_as_they_were() -> None:
    callbacks = list(gc.callbacks)
    with long_lived_frozen(), long_lived_frozen():
        pass
    assert gc.callbacks == callbacks and gc.get_freeze_count() == 0
