"""The anytime search's progress lines: one clock for the whole run."""

from __future__ import annotations

import pytest

from tmpnav.cli.options import search_progress


def test_progress_shows_the_runs_clock_not_each_search_phases_own(capsys: pytest.CaptureFixture[str]) -> None:
    now = iter([100.0, 102.2, 102.6, 104.0])  # the run starts at 100 s
    show = search_progress(clock=lambda: next(now))
    show(2.2, 10.0, None, "first plan")  # the first phase's own clock
    show(0.4, 9.0, 8.0, "improved")  # a second phase restarts its clock at 0
    show(1.8, 9.0, 8.5, "improved")
    times = [float(line.split()[1]) for line in capsys.readouterr().err.splitlines()]
    assert times == [2.2, 2.6, 4.0]
