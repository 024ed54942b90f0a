"""A run's stage times: they add up to its total, which is the run's wall-clock time (issue 57)."""

from __future__ import annotations

import pytest

from tmpnav import results
from tmpnav.results import OTHER, StageTimes


class FakeClock:
    """time.perf_counter that moves only when told."""

    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now

    def tick(self, seconds: float) -> None:
        self.now += seconds


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> FakeClock:
    fake = FakeClock()
    monkeypatch.setattr(results.time, "perf_counter", fake)
    return fake


def test_stages_add_up_to_the_total_and_the_total_is_the_runs_time(clock: FakeClock) -> None:
    """Before, a stage timed inside another counted twice and time between stages not at all: the
    total (their sum) was neither the run's time nor what the search's progress had shown."""
    times = StageTimes()
    with times.timed("load"):
        clock.tick(2.0)
    clock.tick(1.0)  # starting the oracle's workers: in no stage
    with times.timed("planner"):
        clock.tick(3.0)
        with times.timed("oracle"):  # costs asked for inside the planner's time
            clock.tick(4.0)
        clock.tick(0.5)
    assert times.elapsed() == pytest.approx(8.5)  # the run's clock: load excluded
    with times.timed("resimulate"):
        clock.tick(1.0)
    times.close()
    s = times.seconds
    assert s["planner"] == pytest.approx(3.5) and s["oracle"] == pytest.approx(4.0)
    assert s[OTHER] == pytest.approx(1.0)
    assert s["total"] == pytest.approx(9.5)  # wall-clock 11.5 s less load's 2 s
    assert sum(v for k, v in s.items() if k not in ("load", "total")) == pytest.approx(s["total"])


def test_the_budget_counts_the_stages_only(clock: FakeClock) -> None:
    times = StageTimes()
    with times.timed("oracle"):
        clock.tick(2.0)
    clock.tick(5.0)
    assert times.spent() == pytest.approx(2.0)
