"""The certified bound computed beside the search (tmpnav.planning.bound.LaterBound)."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import pytest

from tmpnav.planning import bound as planning_bound
from tmpnav.results import StageTimes
from tmpnav.task.bound import Bound


def _run() -> SimpleNamespace:
    return SimpleNamespace(canonical=SimpleNamespace(oracle=SimpleNamespace(ctx=None)), times=StageTimes())


def test_the_bound_is_computed_in_a_thread_and_waited_for_as_the_bound_stage(monkeypatch):
    release, threads = threading.Event(), []

    def certified(run):
        threads.append(threading.current_thread().name)
        release.wait(5.0)
        return Bound(12.5, "flow")

    monkeypatch.setattr(planning_bound, "library", lambda ctx: None)
    monkeypatch.setattr(planning_bound, "certified_bound", certified)
    run = _run()
    later = planning_bound.LaterBound(run)
    threading.Timer(0.2, release.set).start()
    assert later().value == 12.5
    assert threads == ["tmpnav-bound"]
    assert run.times.seconds["bound"] >= 0.1  # the wait
    assert later() is later()  # computed once


def test_an_error_of_the_bound_is_raised_where_it_is_asked_for(monkeypatch):
    def certified(run):
        raise ValueError("no floors")

    monkeypatch.setattr(planning_bound, "library", lambda ctx: None)
    monkeypatch.setattr(planning_bound, "certified_bound", certified)
    later = planning_bound.LaterBound(_run())
    with pytest.raises(ValueError, match="no floors"):
        later()
