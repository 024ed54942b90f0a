"""The anytime search's progress lines and the summary's times: one clock for the whole run."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

import pytest

from tests.test_cli_plan import ROOT, tmpnav
from tmpnav.cli.options import search_progress

CORRIDOR = ROOT / "configs" / "corridor-2robots.yaml"


def test_progress_shows_the_runs_clock(capsys: pytest.CaptureFixture[str]) -> None:
    """The seconds told are the run's (tmpnav.results.StageTimes.elapsed), whatever phase of the
    search tells them: the clock that the summary's total ends."""
    show = search_progress()
    show(2.2, 10.0, None, "first plan")
    show(2.6, 9.0, 8.0, "improved")
    times = [float(line.split()[1]) for line in capsys.readouterr().err.splitlines()]
    assert times == [2.2, 2.6]


@pytest.mark.slow
def test_a_real_plans_times_agree(tmp_path: Path) -> None:
    """`make demo` printed "search 57.0 s" and then a total of 49.36 s: the progress counted from
    before the scenario was read, the total only the stages' blocks. Now the stages, and the
    time in none of them, add up to the total, the run's wall-clock time, and the search's last
    progress line lies within it."""
    started = time.perf_counter()
    proc = tmpnav(
        "plan", str(CORRIDOR), "--search", "anytime", "--costs", "table", "--objective", "cost",
        "--cache-dir", str(tmp_path / "cache"), "-o", str(tmp_path / "out"),
    )  # fmt: skip
    wall = time.perf_counter() - started
    assert proc.returncode == 0, proc.stderr
    timings = json.loads((tmp_path / "out" / "plan.json").read_text())["timings"]
    total = timings["total"]
    assert sum(v for k, v in timings.items() if k not in ("load", "total")) == pytest.approx(total, abs=1e-5)
    assert 0 < total + timings["load"] < wall
    searched = [float(m[1]) for m in re.finditer(r"^search\s+([\d.]+) s", proc.stderr, re.M)]
    assert searched and max(searched) <= total + 0.05
    # the summary's table: the same figures, adding up to its total (each rounded to 0.01 s)
    lines = proc.stdout.splitlines()
    i = next(i for i, line in enumerate(lines) if line.startswith("time [s]  "))
    names, values = lines[i].split()[2:], [float(v) for v in lines[i + 1].split()]
    shown = dict(zip(names, values, strict=True))
    assert "other" in shown
    stages = [v for k, v in shown.items() if k not in ("total", "(load)")]
    assert sum(stages) == pytest.approx(shown["total"], abs=0.005 * len(stages) + 1e-9)
