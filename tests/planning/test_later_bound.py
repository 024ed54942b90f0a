"""The certified bound computed beside the search, in a process of its own
(tmpnav.planning.bound.LaterBound)."""

from __future__ import annotations

import os
from types import SimpleNamespace

import pytest

from tmpnav.planning import bound as planning_bound
from tmpnav.results import StageTimes
from tmpnav.task.bound import Bound


def _run(partners_fused: bool = True) -> SimpleNamespace:
    oracle = SimpleNamespace(ctx=None, let_go=[])
    oracle.let_go_of_workers = lambda: oracle.let_go.append(True)
    return SimpleNamespace(
        canonical=SimpleNamespace(oracle=oracle),
        scenario=SimpleNamespace(models=SimpleNamespace(partners_fused=partners_fused)),
        times=StageTimes(),
    )


@pytest.fixture
def no_library(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(planning_bound, "library", lambda ctx: None)


def test_the_bound_is_computed_in_a_forked_process_and_waited_for_as_the_bound_stage(monkeypatch, no_library):
    here = os.getpid()
    monkeypatch.setattr(planning_bound, "certified_bound", lambda run: Bound(float(os.getpid() != here), "flow"))
    run = _run()
    later = planning_bound.LaterBound(run)
    later.start()
    assert later().value == 1.0  # computed in another process
    assert "bound" in run.times.seconds
    assert later() is later()  # asked for once


def test_a_bound_never_started_is_computed_in_line(monkeypatch, no_library):
    here = os.getpid()
    monkeypatch.setattr(planning_bound, "certified_bound", lambda run: Bound(float(os.getpid() != here), "flow"))
    assert planning_bound.LaterBound(_run())().value == 0.0


def test_an_error_of_the_bound_is_raised_where_it_is_asked_for(monkeypatch, no_library):
    def certified(run):
        raise ValueError("no floors")

    monkeypatch.setattr(planning_bound, "certified_bound", certified)
    later = planning_bound.LaterBound(_run())
    later.start()
    with pytest.raises(ValueError, match="no floors"):
        later()


def test_a_bound_process_that_dies_is_an_error_not_a_hang(monkeypatch, no_library):
    monkeypatch.setattr(planning_bound, "certified_bound", lambda run: os._exit(3))
    later = planning_bound.LaterBound(_run())
    later.start()
    with pytest.raises(RuntimeError, match="exit code 3"):
        later()


@pytest.mark.parametrize("partners_fused", [True, False])
def test_the_oracle_workers_are_let_go_at_the_fork_when_no_paired_move_is_to_come(
    monkeypatch, no_library, partners_fused
):
    """Without paired moves the single moves' table was the workers' last wave: they are let go
    before the bound's process forks beside them; with paired moves the search needs them."""
    monkeypatch.setattr(planning_bound, "certified_bound", lambda run: Bound(1.0, "flow"))
    run = _run(partners_fused)
    later = planning_bound.LaterBound(run)
    later.start()
    assert later().value == 1.0
    assert run.canonical.oracle.let_go == ([] if partners_fused else [True])
